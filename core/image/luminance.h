#pragma once
// Rec. 709 luminance Y = 0.2126 R + 0.7152 G + 0.0722 B, in double (no overflow for any
// float): the one definition for outlier rules, noise estimates, guides and metrics.
#include <cmath>

namespace mcr {

inline double luminance(const float* rgb) {
  return 0.2126 * double(rgb[0]) + 0.7152 * double(rgb[1]) + 0.0722 * double(rgb[2]);
}
inline bool finite3(const float* rgb) { return std::isfinite(rgb[0]) && std::isfinite(rgb[1]) && std::isfinite(rgb[2]); }

}  // namespace mcr
