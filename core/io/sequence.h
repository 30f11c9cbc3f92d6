#pragma once
// Frame sequences: "shot_####.exr" or "shot_%04d.exr" with a frame range.
#include <string>
#include <vector>

namespace mcr {

struct FrameRange {
  int first = 0, last = -1;
  int count() const { return last - first + 1; }
};

bool is_sequence_pattern(const std::string& path);
// Substitutes the frame number in the first run (#### pads to the number of #, any
// width; %0Nd as printf);
// throws InvalidArgument for a %0Nd wider than 16 digits.
std::string sequence_path(const std::string& pattern, int frame);
// "1-16", "7" (one frame); throws InvalidArgument.
FrameRange parse_frame_range(const std::string& text);

}  // namespace mcr
