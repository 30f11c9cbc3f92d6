#pragma once
// A plain brute-force SSIM (full 2D window, explicit mirror indexing, no separability): the
// oracle of the metrics tests and of the evaluation tests.
#include <algorithm>
#include <cmath>

#include "image/image.h"

namespace mcr::testutil {

inline constexpr double kC1 = 0.0001;  // (0.01 * 1)^2
inline constexpr double kC2 = 0.0009;  // (0.03 * 1)^2

// Mirror without repeating the edge pixel, bouncing until the index lands inside [0, n).
inline int mirror(int i, int n) {
  if (n == 1) return 0;
  while (i < 0 || i >= n) {
    if (i < 0) i = -i;
    if (i >= n) i = 2 * (n - 1) - i;
  }
  return i;
}

inline double clamped(float v) {
  if (!std::isfinite(v)) return 0.0;
  return std::min(1.0, std::max(0.0, double(v)));
}

inline double brute_force_ssim(const Image& a, const Image& b) {
  double kernel[11][11];
  double total = 0.0;
  for (int j = 0; j < 11; ++j)
    for (int i = 0; i < 11; ++i) {
      const double dx = i - 5, dy = j - 5;
      kernel[j][i] = std::exp(-(dx * dx + dy * dy) / (2.0 * 1.5 * 1.5));
      total += kernel[j][i];
    }
  for (auto& row : kernel)
    for (double& k : row) k /= total;

  const int w = a.width(), h = a.height();
  double channel_sum = 0.0;
  for (int c = 0; c < 3; ++c) {
    double map_sum = 0.0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double mx = 0, my = 0, exx = 0, eyy = 0, exy = 0;
        for (int j = 0; j < 11; ++j)
          for (int i = 0; i < 11; ++i) {
            const int sx = mirror(x + i - 5, w), sy = mirror(y + j - 5, h);
            const double p = clamped(a.at(sx, sy, c)), q = clamped(b.at(sx, sy, c));
            const double k = kernel[j][i];
            mx += k * p;
            my += k * q;
            exx += k * p * p;
            eyy += k * q * q;
            exy += k * p * q;
          }
        const double vx = exx - mx * mx, vy = eyy - my * my, cxy = exy - mx * my;
        map_sum += ((2 * mx * my + kC1) * (2 * cxy + kC2)) /
                   ((mx * mx + my * my + kC1) * (vx + vy + kC2));
      }
    channel_sum += map_sum / (double(w) * h);
  }
  return channel_sum / 3.0;
}

}  // namespace mcr::testutil
