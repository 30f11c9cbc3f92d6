#pragma once
// The upper median of a frame's worth of values (element n/2 of their order; 0 when there are
// none), reordering them: the frame statistics pwaf and guided take, gathered band by band in a
// tiled run (pipeline/tiled_run.h) and kept as floats between passes (the median of the
// rounded values is the rounded median: rounding keeps the order).
#include <algorithm>
#include <cstddef>
#include <vector>

namespace mcr {

inline double upper_median(std::vector<float>& v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return double(*mid);
}

}  // namespace mcr
