#include "io/output_guard.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <utility>

#include "util/error.h"

namespace mcr {

namespace fs = std::filesystem;

namespace {

const char* kind_of(mode_t m) {
  if (S_ISDIR(m)) return "a directory";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISFIFO(m)) return "a FIFO";
  if (S_ISSOCK(m)) return "a socket";
  return "not a regular file";
}

using FileId = std::pair<dev_t, ino_t>;

// Canonical path (symlinks resolved, "." and ".." gone) and, when the file exists,
// its identity (hard links): two spellings of one file agree on one of them.
struct Identity {
  fs::path path;
  bool has_path = false, has_id = false;
  FileId id{};
};

Identity identify(const std::string& p) {
  Identity r;
  std::error_code ec;
  r.path = fs::weakly_canonical(fs::absolute(p), ec);
  r.has_path = !ec;
  struct stat st;
  if (::stat(p.c_str(), &st) == 0) {
    r.has_id = true;
    r.id = {st.st_dev, st.st_ino};
  }
  return r;
}

// same(i, j): the message when outputs i < j are one file.
void check_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs,
                   const std::function<std::string(std::size_t, std::size_t)>& same) {
  std::map<fs::path, const std::string*> in_path;
  std::map<FileId, const std::string*> in_id;
  for (const std::string& in : inputs) {
    const Identity id = identify(in);
    if (id.has_path) in_path.emplace(id.path, &in);
    if (id.has_id) in_id.emplace(id.id, &in);
  }
  std::map<fs::path, std::size_t> out_path;
  std::map<FileId, std::size_t> out_id;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const std::string& output = outputs[i];
    if (output.empty()) throw Error(Errc::InvalidArgument, "no output path given");
    const Identity id = identify(output);
    const std::string* input = nullptr;
    if (id.has_path)
      if (auto it = in_path.find(id.path); it != in_path.end()) input = it->second;
    if (!input && id.has_id)
      if (auto it = in_id.find(id.id); it != in_id.end()) input = it->second;
    if (input)
      throw Error(Errc::InvalidArgument,
                  "output '" + output + "' is the input '" + *input + "': inputs are never overwritten");
    if (id.has_path)
      if (auto [it, fresh] = out_path.emplace(id.path, i); !fresh) throw Error(Errc::InvalidArgument, same(it->second, i));
    if (id.has_id)
      if (auto [it, fresh] = out_id.emplace(id.id, i); !fresh) throw Error(Errc::InvalidArgument, same(it->second, i));
    check_output_target(output);
    std::error_code ec;
    const fs::path dir = fs::absolute(output).parent_path();
    if (!fs::is_directory(dir, ec))
      throw Error(Errc::WriteFailed, "cannot write '" + output + "': directory '" + dir.string() + "' does not exist");
    if (::access(dir.c_str(), W_OK) != 0)
      throw Error(Errc::WriteFailed, "cannot write '" + output + "': directory '" + dir.string() + "' is not writable");
  }
}

}  // namespace

void check_output_target(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode)) return;  // new (or dangling) or a regular file
  throw Error(Errc::WriteFailed, "cannot write '" + path + "': it is " + kind_of(st.st_mode) +
                                     " (an output must be a regular file or a new path)");
}

void check_output_paths(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
  check_outputs(outputs, inputs, [&](std::size_t i, std::size_t j) {
    return "outputs '" + outputs[i] + "' and '" + outputs[j] + "' are the same file";
  });
}

void check_output_path(const std::string& output, const std::vector<std::string>& inputs) {
  check_output_paths({output}, inputs);
}

void check_sequence_outputs(const std::string& pattern, const FrameList& frames,
                            const std::vector<std::string>& inputs) {
  std::vector<std::string> outputs;
  for (int f : frames.frames()) outputs.push_back(sequence_path(pattern, f));
  check_outputs(outputs, inputs, [&](std::size_t i, std::size_t j) {
    return "output pattern '" + pattern + "' gives frames " + std::to_string(frames.frames()[i]) + " and " +
           std::to_string(frames.frames()[j]) + " the same file '" + outputs[j] + "'";
  });
}

std::string write_error_text(int err) {
  const std::string sys = std::strerror(err);
  switch (err) {
    case ENOSPC: return "the disk is full (" + sys + ")";
    case EDQUOT: return "the disk quota is used up (" + sys + ")";
    case EFBIG: return "the file size limit is reached (" + sys + ")";
    default: return sys;
  }
}

}  // namespace mcr
