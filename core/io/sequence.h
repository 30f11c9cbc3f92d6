#pragma once
// Frame sequences: "shot_####.exr" or "shot_%04d.exr" with a frame range.
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace mcr {

// The frames of a run, in increasing order, each once.
class FrameList {
 public:
  // first..last; throws InvalidArgument when last < first or the span is over kMaxFrames.
  static FrameList span(int first, int last, const std::string& what = "frame range");
  explicit FrameList(std::vector<int> frames) : frames_(std::move(frames)) {}
  const std::vector<int>& frames() const { return frames_; }
  std::size_t size() const { return frames_.size(); }
  int first() const { return frames_.front(); }
  int last() const { return frames_.back(); }
  // Every frame follows the one before (what a temporal filter's one-frame motion needs).
  bool consecutive() const;
  // "1-16", "1-16x2" or "1,5,9": the shortest text parse_frame_list reads back as this list.
  std::string text() const;

 private:
  std::vector<int> frames_;
};

// At most this many frames in one run: a typo like 1-2000000000 is an error, not 8 GB of frame numbers.
constexpr std::size_t kMaxFrames = 1000000;

bool is_sequence_pattern(const std::string& path);
// Substitutes the frame number in the first run (#### pads to the number of #, any
// width; %0Nd as printf);
// throws InvalidArgument for a %0Nd wider than 16 digits.
std::string sequence_path(const std::string& pattern, int frame);
// Frames as oiiotool writes them, comma-separated parts: "7", "1-16", "1-16x2" (every 2nd:
// 1, 3, .., 15), "1-16y2" (the frames x2 skips: 2, 4, .., 16), "1-4,9,12-16". Unlike
// oiiotool, the frames must come in increasing order, each once (history runs forward,
// every frame has its own output). Throws InvalidArgument naming --frames and the text.
FrameList parse_frame_list(const std::string& text);

}  // namespace mcr
