#include "prepare/sample_limits.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "image/luminance.h"
#include "kernels/window_sums.h"
#include "util/parallel.h"

namespace mcr {

namespace {

// The window's sums without its centre, added pixel by pixel.
void direct(const Image& rgb, int x, int y, int radius, double& s, double& s2, double& n) {
  s = s2 = n = 0;
  for (int qy = std::max(0, y - radius); qy <= std::min(rgb.height() - 1, y + radius); ++qy)
    for (int qx = std::max(0, x - radius); qx <= std::min(rgb.width() - 1, x + radius); ++qx) {
      const float* q = rgb.pixel(qx, qy);
      if ((qx == x && qy == y) || !finite3(q)) continue;
      const double v = luminance(q);
      s += v;
      s2 += v * v;
      n += 1.0;
    }
}

}  // namespace

void firefly_limits(const Image& rgb, int radius, double k, int nthreads, std::vector<float>& limit) {
  const int w = rgb.width(), h = rgb.height();
  limit.resize(std::size_t(w) * std::size_t(h));
  // Kept between frames by the calling thread (a sequence's frames are the same size).
  // (References: a thread_local named inside the workers would be each worker's own.)
  thread_local WindowSums kept_sum, kept_sq;
  WindowSums& sum = kept_sum;
  WindowSums& sq = kept_sq;
  sum.reset(w, h, true);
  sq.reset(w, h, false);
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float* p = rgb.pixel(x, y);
      if (!finite3(p)) continue;  // left at 0, counted 0
      const double v = luminance(p);
      sum.set(x, y, v, 1.0);
      sq.set(x, y, v * v, 1.0);
    }
  });
  sum.sum_windows(radius, nthreads);
  sq.sum_windows(radius, nthreads);
  constexpr double kMax = double(std::numeric_limits<float>::max());
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float* p = rgb.pixel(x, y);
      double s = sum.value(x, y), s2 = sq.value(x, y), n = sum.count(x, y);
      if (finite3(p)) {  // the centre is not its own neighbour
        const double v = luminance(p);
        s -= v;
        s2 -= v * v;
        n -= 1.0;
      }
      float& out = limit[std::size_t(y) * std::size_t(w) + std::size_t(x)];
      // A centre that dominates its window (a firefly of 1e30 among 0.5s) would leave
      // only rounding after the subtraction: those few pixels are summed directly.
      if (finite3(p)) {
        const double v = luminance(p);
        if (std::fabs(v) * 1e-9 > std::fabs(s) || v * v * 1e-9 > std::fabs(s2)) direct(rgb, x, y, radius, s, s2, n);
      }
      if (n < 2.5) {
        out = std::numeric_limits<float>::infinity();
        continue;
      }
      const double mu = s / n;
      const double sd = std::sqrt(std::max(s2 / n - mu * mu, 0.0));
      const double bound = mu + std::max(k * sd, 0.01 * std::fabs(mu));
      out = std::isfinite(bound) ? float(std::min(bound, kMax)) : float(kMax);
    }
  });
}

void neighbourhood_caps(const Image& rgb, const std::vector<std::uint8_t>& flags, std::uint8_t mask, int nthreads,
                        std::vector<float>& cap) {
  const int w = rgb.width(), h = rgb.height();
  cap.resize(std::size_t(w) * std::size_t(h));
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
      double m = std::numeric_limits<double>::infinity();
      if (flags[i] & mask) {
        m = -std::numeric_limits<double>::infinity();
        for (int qy = std::max(0, y - 1); qy <= std::min(h - 1, y + 1); ++qy)
          for (int qx = std::max(0, x - 1); qx <= std::min(w - 1, x + 1); ++qx) {
            const float* q = rgb.pixel(qx, qy);
            if (finite3(q)) m = std::max(m, luminance(q));
          }
        if (!(m > -std::numeric_limits<double>::infinity())) m = std::numeric_limits<double>::infinity();  // none finite
      }
      cap[i] = std::isinf(m) ? std::numeric_limits<float>::infinity() : float(std::min(m, double(std::numeric_limits<float>::max())));
    }
  });
}

}  // namespace mcr
