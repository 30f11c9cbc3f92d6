#include "io/sequence.h"

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
// printf's "%0*d": the frame zero-padded to width digits (a sign counts), never cut.
std::string padded(int frame, std::size_t width) {
  const std::string digits = std::to_string(frame < 0 ? -(long long)frame : (long long)frame);
  const std::size_t sign = frame < 0 ? 1 : 0;
  const std::size_t zeros = width > digits.size() + sign ? width - digits.size() - sign : 0;
  return (sign ? "-" : "") + std::string(zeros, '0') + digits;
}
}  // namespace

bool is_sequence_pattern(const std::string& path) {
  return std::regex_search(path, kHashes) || std::regex_search(path, kPrintf);
}

std::string sequence_path(const std::string& pattern, int frame) {
  std::smatch m;
  if (std::regex_search(pattern, m, kHashes)) return m.prefix().str() + padded(frame, std::size_t(m.length(0))) + m.suffix().str();
  if (std::regex_search(pattern, m, kPrintf)) {
    const int width = m[1].length() ? to_int(m[1].str(), "frame pattern '" + pattern + "'") : 0;
    if (width > 16) throw Error(Errc::InvalidArgument, "frame pattern '" + pattern + "': width " + m[1].str() + " is too wide");
    return m.prefix().str() + padded(frame, std::size_t(width)) + m.suffix().str();
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
