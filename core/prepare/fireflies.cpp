#include "prepare/fireflies.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "util/parallel.h"

namespace mcr {

Image suppress_fireflies(const Image& colour, int radius, double k, int nthreads, std::size_t* clamped) {
  const int w = colour.width(), h = colour.height();
  Image out = colour.channels() == 3 ? colour : colour.channel_range(0, 3);
  if (clamped) *clamped = 0;
  if (!(k > 0) || out.empty()) return out;
  // Luminance of every pixel, NaN where a channel is not finite.
  std::vector<double> lum(std::size_t(w) * std::size_t(h));
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float* p = out.pixel(x, y);
      const bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
      lum[std::size_t(y) * w + x] = finite ? 0.2126 * double(p[0]) + 0.7152 * double(p[1]) + 0.0722 * double(p[2])
                                           : std::numeric_limits<double>::quiet_NaN();
    }
  });
  std::vector<unsigned char> hit(lum.size(), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    const int y0 = std::max(0, y - radius), y1 = std::min(h - 1, y + radius);
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      const double yp = lum[i];
      if (!(yp > 0)) continue;  // NaN, zero or negative: nothing to clamp
      const int x0 = std::max(0, x - radius), x1 = std::min(w - 1, x + radius);
      double sum = 0;
      std::size_t n = 0;
      for (int yy = y0; yy <= y1; ++yy)
        for (int xx = x0; xx <= x1; ++xx) {
          const double q = lum[std::size_t(yy) * w + xx];
          if ((xx != x || yy != y) && !std::isnan(q)) { sum += q; ++n; }
        }
      if (n < 3) continue;
      const double mu = sum / double(n);
      double var = 0;  // two passes: no cancellation
      for (int yy = y0; yy <= y1; ++yy)
        for (int xx = x0; xx <= x1; ++xx) {
          const double q = lum[std::size_t(yy) * w + xx];
          if ((xx != x || yy != y) && !std::isnan(q)) var += (q - mu) * (q - mu);
        }
      const double lim = mu + std::max(k * std::sqrt(var / double(n)), 0.01 * std::fabs(mu));
      if (!(yp > lim) || !(lim > 0) || !std::isfinite(lim)) continue;
      const double s = lim / yp;  // in (0, 1)
      float* o = out.pixel(x, y);
      for (int c = 0; c < 3; ++c) o[c] = float(double(o[c]) * s);
      hit[i] = 1;
    }
  });
  if (clamped) *clamped = std::size_t(std::count(hit.begin(), hit.end(), 1));
  return out;
}

}  // namespace mcr
