#pragma once
// IEC 61966-2-1 sRGB transfer, computed here: the oracle for OpenColorIO's Standard view of
// Blender's config (display sRGB) in the preview and display-output tests.
#include <algorithm>
#include <cmath>

namespace mcr::testutil {

// Encoding of a linear value in [0, 1], and its inverse.
inline double srgb_encode(double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055; }
inline double srgb_decode(double e) { return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4); }

// The integer code of a linear value at `levels` - 1 full scale: clamp to [0, 1], encode, round.
inline int srgb_code(double linear, int levels = 256) {
  return int(std::lround((levels - 1) * srgb_encode(std::clamp(linear, 0.0, 1.0))));
}

}  // namespace mcr::testutil
