#include "io/atomic_write.h"

#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <map>
#include <utility>

#include "util/error.h"

namespace mcr {

namespace fs = std::filesystem;

namespace {
// The temp file currently being written, readable from a signal handler.
char g_pending[4096];
volatile std::sig_atomic_t g_has_pending = 0;

void set_pending(const std::string& p) {
  g_has_pending = 0;
  std::strncpy(g_pending, p.c_str(), sizeof(g_pending) - 1);
  g_pending[sizeof(g_pending) - 1] = '\0';
  g_has_pending = 1;
}

std::string temp_prefix(const fs::path& target) {
  return "." + target.filename().string() + ".mcrecon-tmp.";
}
}  // namespace

std::string temp_path_for(const std::string& path) {
  const fs::path target(path);
  return (target.parent_path() / (temp_prefix(target) + std::to_string(::getpid()))).string();
}

void remove_pending_temp() noexcept {
  if (g_has_pending) ::unlink(g_pending);
}

void check_output_paths(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
  // Each input once (a sequence checks every output against every input): its
  // canonical path, and its file identity when it exists (hard links).
  std::map<fs::path, const std::string*> by_path;
  std::map<std::pair<dev_t, ino_t>, const std::string*> by_id;
  for (const std::string& in : inputs) {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(fs::absolute(in), ec);
    if (!ec) by_path.emplace(p, &in);
    struct stat st;
    if (::stat(in.c_str(), &st) == 0) by_id.emplace(std::make_pair(st.st_dev, st.st_ino), &in);
  }
  for (const std::string& output : outputs) {
    if (output.empty()) throw Error(Errc::InvalidArgument, "no output path given");
    std::error_code ec;
    const std::string* same = nullptr;
    const fs::path out = fs::weakly_canonical(fs::absolute(output), ec);
    if (!ec)
      if (auto it = by_path.find(out); it != by_path.end()) same = it->second;
    struct stat st;
    if (!same && ::stat(output.c_str(), &st) == 0)
      if (auto it = by_id.find(std::make_pair(st.st_dev, st.st_ino)); it != by_id.end()) same = it->second;
    if (same)
      throw Error(Errc::InvalidArgument, "output '" + output + "' is the input '" + *same + "': inputs are never overwritten");
    fs::path dir = fs::absolute(output).parent_path();
    if (!fs::is_directory(dir, ec))
      throw Error(Errc::WriteFailed, "cannot write '" + output + "': directory '" + dir.string() + "' does not exist");
    if (::access(dir.c_str(), W_OK) != 0)
      throw Error(Errc::WriteFailed, "cannot write '" + output + "': directory '" + dir.string() + "' is not writable");
    if (fs::is_directory(output, ec))
      throw Error(Errc::WriteFailed, "cannot write '" + output + "': it is a directory");
  }
}

void check_output_path(const std::string& output, const std::vector<std::string>& inputs) {
  check_output_paths({output}, inputs);
}

void write_atomic(const OIIO::ImageBuf& buf, const std::string& path, const std::string& format) {
  const fs::path target(path);
  std::error_code ec;
  // Leftovers of killed runs for this target.
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  const std::string prefix = temp_prefix(target);
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename().string().rfind(prefix, 0) == 0) fs::remove(e.path(), ec);

  const std::string tmp = temp_path_for(path);
  std::string fmt = format;
  if (fmt.empty()) {
    std::string ext = target.extension().string();
    fmt = ext.size() > 1 ? ext.substr(1) : "openexr";
    if (fmt == "exr") fmt = "openexr";
  }
  set_pending(tmp);
  const bool ok = buf.write(tmp, OIIO::TypeUnknown, fmt);
  if (!ok) {
    const std::string msg = buf.geterror();
    fs::remove(tmp, ec);
    g_has_pending = 0;
    throw Error(Errc::WriteFailed, "cannot write '" + path + "': " + msg);
  }
  fs::rename(tmp, target, ec);
  g_has_pending = 0;
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(Errc::WriteFailed, "cannot write '" + path + "': rename failed: " + ec.message());
  }
}

}  // namespace mcr
