#pragma once
// The albedo a colour is divided by (prepare/demodulation.h gives the rule and why), here so
// that the kernels that read a colour over its albedo (kernels/noise_scale.h) take the same one.
#include <algorithm>
#include <cmath>

namespace mcr {

constexpr float kAlbedoCeiling = 1.0f;
constexpr double kDefaultAlbedoFloor = 0.01;  // the albedo_floor parameter's default

inline float demodulation_albedo(float v, float floor, float ceiling = kAlbedoCeiling) {
  return (v - v == 0.0f) ? std::min(std::max(v, floor), ceiling) : 1.0f;
}

// The divisor of one colour value c over albedo v (the rule above). 2^-126 is FLT_MIN, a
// normal float (no flush-to-zero concern), and |c| * 2^-126 is exact where it matters.
inline float demodulation_divisor(float v, float c, float floor, float ceiling = kAlbedoCeiling) {
  const float need = (c - c == 0.0f) ? std::fabs(c) * 0x1p-126f : 0.0f;
  return std::max(demodulation_albedo(v, floor, ceiling), need);
}

}  // namespace mcr
