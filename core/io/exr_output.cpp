#include "io/exr_output.h"

#include <cctype>
#include <cmath>
#include <cstdlib>

#include "io/frame_reader.h"
#include "util/error.h"

namespace mcr {

namespace {

constexpr const char* kCompressions[] = {"none", "rle", "zip", "zips", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"};

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

[[noreturn]] void bad_compression(const std::string& text, const std::string& why) {
  std::string names;
  for (const char* c : kCompressions) names += (names.empty() ? "" : ", ") + std::string(c);
  throw Error(Errc::InvalidArgument, "compression '" + text + "' " + why + "; valid: " + names +
                                         " (zip and zips take a level :1 to :9, dwaa and dwab a quality :N > 0, "
                                         "e.g. zip:9, dwaa:45)");
}

}  // namespace

std::string checked_exr_compression(const std::string& text) {
  const std::string t = lower(text);
  const auto colon = t.find(':');
  const std::string name = t.substr(0, colon);
  bool known = false;
  for (const char* c : kCompressions) known = known || name == c;
  if (!known) bad_compression(text, "is not an OpenEXR compression");
  if (colon == std::string::npos) return t;
  const std::string level = t.substr(colon + 1);
  char* end = nullptr;
  const double v = std::strtod(level.c_str(), &end);
  const bool number = !level.empty() && *end == '\0' && std::isfinite(v);
  if (name == "zip" || name == "zips") {
    if (!number || v != std::floor(v) || v < 1 || v > 9) bad_compression(text, "has a bad level (zip takes 1 to 9)");
  } else if (name == "dwaa" || name == "dwab") {
    if (!number || !(v > 0)) bad_compression(text, "has a bad quality (dwa takes a number > 0)");
  } else {
    bad_compression(text, "takes no level (only zip, zips, dwaa and dwab do)");
  }
  return t;
}

void check_exr_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  if (base.size() > 4 && lower(base.substr(base.size() - 4)) == ".exr") return;
  throw Error(Errc::InvalidArgument, "output '" + path + "': mcrecon writes OpenEXR; use a .exr name");
}

std::string incomplete_file_reason(const std::string& path) {
  ReadOptions all;
  all.require_colour = false;  // any channels: the question is only whether every pixel decodes
  try {
    read_frame(path, all);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace mcr
