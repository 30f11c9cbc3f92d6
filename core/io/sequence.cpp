#include "io/sequence.h"

#include <cstdio>
#include <regex>

#include "util/error.h"

namespace mcr {

namespace {
const std::regex kHashes("#+");
const std::regex kPrintf("%0?([0-9]*)d");

// std::stoi, but a number that does not fit an int is the user's error, not std::out_of_range.
int to_int(const std::string& digits, const std::string& what) {
  try {
    return std::stoi(digits);
  } catch (const std::out_of_range&) {
    throw Error(Errc::InvalidArgument, what + ": " + digits + " is out of range");
  }
}
}  // namespace

bool is_sequence_pattern(const std::string& path) {
  return std::regex_search(path, kHashes) || std::regex_search(path, kPrintf);
}

std::string sequence_path(const std::string& pattern, int frame) {
  std::smatch m;
  if (std::regex_search(pattern, m, kHashes)) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%0*d", int(m.length(0)), frame);
    return m.prefix().str() + buf + m.suffix().str();
  }
  if (std::regex_search(pattern, m, kPrintf)) {
    const int width = m[1].length() ? to_int(m[1].str(), "frame pattern '" + pattern + "'") : 0;
    if (width > 16) throw Error(Errc::InvalidArgument, "frame pattern '" + pattern + "': width " + m[1].str() + " is too wide");
    char buf[32];
    std::snprintf(buf, sizeof buf, "%0*d", width, frame);
    return m.prefix().str() + buf + m.suffix().str();
  }
  return pattern;
}

FrameRange parse_frame_range(const std::string& text) {
  static const std::regex range(R"(^\s*(-?\d+)\s*(?:-\s*(-?\d+))?\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, range))
    throw Error(Errc::InvalidArgument, "--frames expects A-B or A, got '" + text + "'");
  FrameRange r;
  r.first = to_int(m[1].str(), "--frames '" + text + "'");
  r.last = m[2].matched ? to_int(m[2].str(), "--frames '" + text + "'") : r.first;
  if (r.last < r.first)
    throw Error(Errc::InvalidArgument, "--frames '" + text + "': the last frame comes before the first");
  return r;
}

}  // namespace mcr
