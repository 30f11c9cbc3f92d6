#include "io/sequence.h"

#include <cstdio>
#include <regex>

#include "util/error.h"

namespace mcr {

namespace {
const std::regex kHashes("#+");
const std::regex kPrintf("%0?([0-9]*)d");
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
    const int width = m[1].length() ? std::stoi(m[1].str()) : 0;
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
  r.first = std::stoi(m[1].str());
  r.last = m[2].matched ? std::stoi(m[2].str()) : r.first;
  if (r.last < r.first)
    throw Error(Errc::InvalidArgument, "--frames '" + text + "': the last frame comes before the first");
  return r;
}

}  // namespace mcr
