#pragma once
// How a filter's time and memory grow with the frame: a sample frame enlarged by mirrored
// tiling (every pass, the deep samples and the light field alike), so that the content per
// pixel, and with it the work per pixel, stays that of the sample (interpolating a noisy frame
// up would smooth its noise and change what adaptive filters do).
#include <functional>
#include <string>
#include <vector>

#include "filters/filter.h"

namespace mcr {

// `src` mirrored (... c b a | a b c | c b a ...) to width x height.
Frame mirrored_tiling(const Frame& src, int width, int height);

struct ScalingRow {
  std::string filter, input;  // input: "flat", "deep", "lightfield"
  int width = 0, height = 0;
  double seconds = 0;          // best of the repeats, filter only
  double peak_memory_mb = -1;  // resident memory the run added at its peak
};

struct ScalingFit {
  std::string filter, input;
  double slope = 0;                        // d log(seconds) / d log(pixels): 1 = linear in pixels
  double seconds_per_megapixel = 0;        // at the largest size
  double peak_memory_mb_per_megapixel = -1;
};

// Least-squares slope of log(seconds) against log(pixels) over `rows` of one filter and input.
ScalingFit fit_scaling(const std::vector<ScalingRow>& rows);

// Runs `filter` on `src` tiled to each size x size; `progress` gets a line per run.
std::vector<ScalingRow> measure_scaling(Filter& filter, const Frame& src, const std::string& input,
                                        const std::vector<int>& sizes, int nthreads, int repeat,
                                        const std::function<void(const std::string&)>& progress = {});

}  // namespace mcr
