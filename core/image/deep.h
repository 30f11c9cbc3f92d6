#pragma once
// Per-sample (deep) buffer: a variable number of samples per pixel, channels
// stored as separate arrays (structure of arrays) indexed through prefix offsets,
// so a per-sample sweep reads one channel of all samples contiguously.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace mcr {

struct DeepSamples {
  int width = 0, height = 0;
  std::vector<std::string> channel_names;  // e.g. R G B A Z dx dy
  std::vector<std::uint64_t> offsets;      // width*height+1 prefix sums of sample counts
  std::vector<std::vector<float>> values;  // values[channel][sample]
  // Header attributes named "mcrecon:*" (the camera for the sweep's circle of confusion:
  // mcrecon:lens_mm, mcrecon:fstop, mcrecon:focus_distance, mcrecon:sensor_width_mm), as text.
  std::map<std::string, std::string> attributes;

  std::uint64_t total_samples() const { return offsets.empty() ? 0 : offsets.back(); }
  std::uint32_t samples(int x, int y) const {
    const std::size_t p = std::size_t(y) * std::size_t(width) + std::size_t(x);
    return std::uint32_t(offsets[p + 1] - offsets[p]);
  }
  std::uint64_t first(int x, int y) const { return offsets[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
  int channel(const std::string& name) const;  // -1 when absent
};

}  // namespace mcr
