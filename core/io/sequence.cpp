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

FrameList FrameList::span(int first, int last, const std::string& what) {
  if (last < first)
    throw Error(Errc::InvalidArgument, what + " " + std::to_string(first) + "-" + std::to_string(last) +
                                           ": the last frame comes before the first");
  const long long n = (long long)last - first + 1;  // 64-bit: a span ending at INT_MAX ends
  if (n > (long long)kMaxFrames)
    throw Error(Errc::InvalidArgument, what + " " + std::to_string(first) + "-" + std::to_string(last) + " holds " +
                                           std::to_string(n) + " frames, more than " + std::to_string(kMaxFrames));
  std::vector<int> f;
  f.reserve(std::size_t(n));
  for (long long i = first; i <= last; ++i) f.push_back(int(i));
  return FrameList(std::move(f));
}

bool FrameList::consecutive() const {
  for (std::size_t i = 1; i < frames_.size(); ++i)
    if ((long long)frames_[i] != (long long)frames_[i - 1] + 1) return false;
  return true;
}

std::string FrameList::text() const {
  if (frames_.empty()) return "";
  if (frames_.size() == 1) return std::to_string(frames_[0]);
  const long long step = (long long)frames_[1] - frames_[0];
  bool even = true;
  for (std::size_t i = 2; i < frames_.size(); ++i) even = even && (long long)frames_[i] - frames_[i - 1] == step;
  const std::string span = std::to_string(first()) + "-" + std::to_string(last());
  if (even) return step == 1 ? span : span + "x" + std::to_string(step);
  std::string t;
  for (int f : frames_) t += (t.empty() ? "" : ",") + std::to_string(f);
  return t;
}

FrameList parse_frame_list(const std::string& text) {
  static const std::regex part(R"(^\s*(-?\d+)\s*(?:-\s*(-?\d+)\s*(?:([xy])\s*(\d+))?)?\s*$)");
  const std::string syntax = "--frames expects frames as oiiotool writes them (7, 1-16, 1-16x2, 1-16y2, 1,5,9), got '" +
                             text + "'";
  const std::string what = "--frames '" + text + "'";
  std::vector<int> frames;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string piece = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    std::smatch m;
    if (!std::regex_match(piece, m, part)) throw Error(Errc::InvalidArgument, syntax);
    const int a = to_int(m[1].str(), what);
    const int b = m[2].matched ? to_int(m[2].str(), what) : a;
    if (b < a)
      throw Error(Errc::InvalidArgument, what + ": " + std::to_string(a) + "-" + std::to_string(b) +
                                             " counts down; frames run forward here (write " + std::to_string(b) +
                                             "-" + std::to_string(a) + ")");
    const int step = m[4].matched ? to_int(m[4].str(), what) : 1;
    if (step < 1) throw Error(Errc::InvalidArgument, what + ": the step must be 1 or more");
    const bool fill = m[3].matched && m[3].str() == "y";  // the frames the step skips
    // x: from a by step; y: every frame x leaves out (none for y1). Each loop adds a frame
    // at least every other turn, so the kMaxFrames check bounds it.
    const long long inc = fill ? 1 : step;
    for (long long f = a; f <= b && !(fill && step == 1); f += inc) {
      if (fill && (f - a) % step == 0) continue;
      if (!frames.empty() && f <= frames.back())
        throw Error(Errc::InvalidArgument, what + ": frame " + std::to_string(f) + " comes after frame " +
                                               std::to_string(frames.back()) +
                                               "; give the frames in increasing order, each once");
      if (frames.size() >= kMaxFrames)
        throw Error(Errc::InvalidArgument, what + " holds more than " + std::to_string(kMaxFrames) + " frames");
      frames.push_back(int(f));
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (frames.empty()) throw Error(Errc::InvalidArgument, what + " holds no frame");
  return FrameList(std::move(frames));
}

}  // namespace mcr
