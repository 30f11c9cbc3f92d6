#include "report/peer_command.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <OpenImageIO/imagebuf.h>

#include "io/atomic_write.h"
#include "util/error.h"

extern char** environ;

namespace mcr {

namespace fs = std::filesystem;

namespace {

const std::map<std::string, Role>& pass_names() {
  static const std::map<std::string, Role> m = {{"colour", Role::Colour},     {"color", Role::Colour},
                                                {"albedo", Role::Albedo},     {"normal", Role::Normal},
                                                {"depth", Role::Depth},       {"position", Role::Position}};
  return m;
}

// "{name}" / "{name.ext}" inside a word: name, ext ("" = default) and where it sits.
struct Placeholder {
  std::size_t at = std::string::npos, length = 0;
  std::string name, ext;
};

std::vector<Placeholder> placeholders(const std::string& word) {
  std::vector<Placeholder> out;
  for (std::size_t open = word.find('{'); open != std::string::npos; open = word.find('{', open + 1)) {
    const std::size_t close = word.find('}', open);
    if (close == std::string::npos) break;
    Placeholder p;
    p.at = open;
    p.length = close - open + 1;
    const std::string body = word.substr(open + 1, close - open - 1);
    const std::size_t dot = body.find('.');
    p.name = body.substr(0, dot);
    p.ext = dot == std::string::npos ? "" : body.substr(dot + 1);
    out.push_back(p);
  }
  return out;
}

std::vector<std::string> split_words(const std::string& text, const std::string& whole) {
  std::vector<std::string> words;
  std::string cur;
  bool in_word = false;
  char quote = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quote == '\'') {
      if (c == '\'') quote = 0; else cur += c;
    } else if (quote == '"') {
      if (c == '"') quote = 0;
      else if (c == '\\' && i + 1 < text.size() && (text[i + 1] == '"' || text[i + 1] == '\\')) cur += text[++i];
      else cur += c;
    } else if (c == '\'' || c == '"') {
      quote = c;
      in_word = true;
    } else if (c == '\\' && i + 1 < text.size()) {
      cur += text[++i];
      in_word = true;
    } else if (c == ' ' || c == '\t') {
      if (in_word) words.push_back(cur);
      cur.clear();
      in_word = false;
    } else {
      cur += c;
      in_word = true;
    }
  }
  if (quote) throw Error(Errc::InvalidArgument, "--peer '" + whole + "': unbalanced quote");
  if (in_word) words.push_back(cur);
  return words;
}

// PFM (OpenImageIO 2.4 reads it but cannot write it): "PF", size, a negative scale for
// little-endian floats, then RGB rows from the bottom up.
void write_pfm(const Image& img, const std::string& path) {
  std::string data = "PF\n" + std::to_string(img.width()) + " " + std::to_string(img.height()) + "\n-1.0\n";
  const std::size_t header = data.size();
  data.resize(header + std::size_t(img.width()) * std::size_t(img.height()) * 3 * sizeof(float));
  char* dst = data.data() + header;
  for (int y = img.height() - 1; y >= 0; --y)
    for (int x = 0; x < img.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = img.at(x, y, img.channels() >= 3 ? c : 0);  // one channel: grey RGB
        std::memcpy(dst, &v, sizeof v);
        dst += sizeof v;
      }
  write_text_atomic(data, path);
}

void write_pass(const Image& img, int channels, const std::string& path, const std::string& format) {
  if (format == "pfm") return write_pfm(img, path);
  OIIO::ImageBuf buf(OIIO::ImageSpec(img.width(), img.height(), channels, OIIO::TypeFloat));
  const Image part = img.channels() == channels ? img : img.channel_range(0, std::min(channels, img.channels()));
  if (part.channels() == channels) {
    buf.set_pixels(buf.roi(), OIIO::TypeFloat, part.data());
  } else {  // a 1-channel pass exported as grey RGB (PFM holds 1 or 3 channels)
    for (int y = 0; y < img.height(); ++y)
      for (int x = 0; x < img.width(); ++x)
        for (int c = 0; c < channels; ++c) buf.setpixel(x, y, c, img.at(x, y, 0));
  }
  write_atomic(buf, path, format, OIIO::TypeFloat);
}

}  // namespace

PeerCommand parse_peer(const std::string& text) {
  const std::size_t eq = text.find('=');
  PeerCommand p;
  if (eq == std::string::npos || eq == 0)
    throw Error(Errc::InvalidArgument, "--peer '" + text + "': expected NAME=COMMAND, e.g. oidn='oidnDenoise --hdr {colour} -o {output}'");
  p.name = text.substr(0, eq);
  for (char c : p.name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-')
      throw Error(Errc::InvalidArgument, "--peer '" + text + "': the name '" + p.name + "' may hold letters, digits, - and _ only");
  p.words = split_words(text.substr(eq + 1), text);
  if (p.words.empty()) throw Error(Errc::InvalidArgument, "--peer '" + text + "': no command after '='");
  bool output = false;
  for (const std::string& w : p.words)
    for (const Placeholder& ph : placeholders(w)) {
      if (!ph.ext.empty() && ph.ext != "exr" && ph.ext != "pfm")
        throw Error(Errc::InvalidArgument, "--peer '" + text + "': {" + ph.name + "." + ph.ext + "}: the format is exr or pfm");
      if (ph.name == "output") output = true;
      else if (!pass_names().count(ph.name))
        throw Error(Errc::InvalidArgument, "--peer '" + text + "': unknown placeholder {" + ph.name +
                                               "} (known: colour, albedo, normal, depth, position, output)");
    }
  if (!output) throw Error(Errc::InvalidArgument, "--peer '" + text + "': the command needs {output}, the file it writes");
  return p;
}

std::vector<Role> peer_roles(const PeerCommand& peer) {
  std::vector<Role> roles;
  for (const std::string& w : peer.words)
    for (const Placeholder& ph : placeholders(w))
      if (ph.name != "output") roles.push_back(pass_names().at(ph.name));
  return roles;
}

std::vector<std::string> peer_argv(const PeerCommand& peer, const Frame& frame, const std::string& dir,
                                   std::string& output) {
  std::vector<std::string> argv;
  for (std::string w : peer.words) {
    std::vector<Placeholder> phs = placeholders(w);
    for (auto it = phs.rbegin(); it != phs.rend(); ++it) {  // back to front: earlier offsets stay valid
      const std::string ext = it->ext.empty() ? "pfm" : it->ext;
      std::string path;
      if (it->name == "output") {
        path = (fs::path(dir) / (peer.name + "_output." + ext)).string();
        output = path;
      } else {
        const Role role = pass_names().at(it->name);
        const Pass& pass = frame.get(role);
        path = (fs::path(dir) / (it->name + "." + ext)).string();
        if (!fs::exists(path)) write_pass(pass.image, pass.image.channels() == 1 && ext == "exr" ? 1 : 3, path,
                                          ext == "exr" ? "openexr" : "pfm");
      }
      w.replace(it->at, it->length, path);
    }
    argv.push_back(w);
  }
  return argv;
}

CommandRun run_timed_command(const std::vector<std::string>& argv, const std::string& log, double timeout_seconds) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);  // never waits for input
  if (!log.empty()) {
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  }
  pid_t pid = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const int err = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (err != 0)
    throw Error(Errc::Internal, "cannot start '" + argv[0] + "': " + std::strerror(err));
  CommandRun run;
  int status = 0;
  struct rusage usage {};
  for (;;) {
    const pid_t r = wait4(pid, &status, WNOHANG, &usage);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw Error(Errc::Internal, "waiting for '" + argv[0] + "': " + std::strerror(errno));
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_seconds && !run.timed_out) {
      kill(pid, SIGKILL);
      run.timed_out = true;
    }
    // 1 ms polls: well under the run times measured, and no busy core taken from the command.
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.peak_memory_mb = double(usage.ru_maxrss) / 1024.0;  // kB on Linux
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  return run;
}

std::string read_log(const std::string& log) {
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string log_tail(const std::string& log, std::size_t max_chars) {
  const std::string s = read_log(log);
  return s.size() > max_chars ? "..." + s.substr(s.size() - max_chars) : s;
}

}  // namespace mcr
