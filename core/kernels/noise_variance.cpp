#include "kernels/noise_variance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "util/parallel.h"

namespace mcr {

std::vector<double> estimate_variance(const Image& colour, const std::vector<std::uint8_t>& valid,
                                      const Image* sample_count, int radius, const Roi& region, int nthreads) {
  const int w = colour.width(), h = colour.height();
  std::vector<double> v(std::size_t(w) * h, 0.0);
  if (region.empty()) return v;
  auto inv_n = [&](int x, int y) {
    if (!sample_count) return 1.0;
    const double n = double(sample_count->pixel(x, y)[0]);
    return std::isfinite(n) && n > 1.0 ? 1.0 / n : 1.0;
  };
  // Residuals on the region grown by the window radius.
  const Roi e_reg = region.grown(radius, w, h);
  const int ew = e_reg.width();
  std::vector<double> e2(std::size_t(ew) * e_reg.height(), 0.0);  // mean over RGB of e_c^2
  std::vector<double> a(e2.size(), 0.0);                           // its expected value / s^2
  parallel_rows(e_reg.y0, e_reg.y1, nthreads, [&](int y) {
    for (int x = e_reg.x0; x < e_reg.x1; ++x) {
      if (!valid[std::size_t(y) * w + x]) continue;
      double mean[3] = {0, 0, 0}, sum_inv = 0;
      int m = 0;
      for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy)
        for (int xx = std::max(0, x - 1); xx <= std::min(w - 1, x + 1); ++xx) {
          if ((xx == x && yy == y) || !valid[std::size_t(yy) * w + xx]) continue;
          const float* q = colour.pixel(xx, yy);
          for (int c = 0; c < 3; ++c) mean[c] += double(q[c]);
          sum_inv += inv_n(xx, yy);
          ++m;
        }
      if (m == 0) continue;
      const float* p = colour.pixel(x, y);
      double s = 0;
      for (int c = 0; c < 3; ++c) {
        const double r = double(p[c]) - mean[c] / m;
        s += r * r;
      }
      const std::size_t j = std::size_t(y - e_reg.y0) * ew + (x - e_reg.x0);
      e2[j] = s / 3.0;
      a[j] = inv_n(x, y) + sum_inv / (double(m) * double(m));
    }
  });
  // Window sums, separable (rows, then columns), each a direct sum: no running sums whose
  // cancellation a 1e30 neighbour could spoil.
  std::vector<double> re(std::size_t(region.width()) * e_reg.height()), ra(re.size());
  const int rw = region.width();
  parallel_rows(e_reg.y0, e_reg.y1, nthreads, [&](int y) {
    const std::size_t row = std::size_t(y - e_reg.y0) * ew;
    for (int x = region.x0; x < region.x1; ++x) {
      double se = 0, sa = 0;
      for (int xx = std::max(e_reg.x0, x - radius); xx <= std::min(e_reg.x1 - 1, x + radius); ++xx) {
        se += e2[row + (xx - e_reg.x0)];
        sa += a[row + (xx - e_reg.x0)];
      }
      re[std::size_t(y - e_reg.y0) * rw + (x - region.x0)] = se;
      ra[std::size_t(y - e_reg.y0) * rw + (x - region.x0)] = sa;
    }
  });
  parallel_rows(region.y0, region.y1, nthreads, [&](int y) {
    for (int x = region.x0; x < region.x1; ++x) {
      double se = 0, sa = 0;
      for (int yy = std::max(e_reg.y0, y - radius); yy <= std::min(e_reg.y1 - 1, y + radius); ++yy) {
        se += re[std::size_t(yy - e_reg.y0) * rw + (x - region.x0)];
        sa += ra[std::size_t(yy - e_reg.y0) * rw + (x - region.x0)];
      }
      const double s2 = sa > 0 ? se / sa : 0.0;
      v[std::size_t(y) * w + x] = std::isfinite(s2) ? s2 * inv_n(x, y) : std::numeric_limits<double>::max();
    }
  });
  return v;
}

}  // namespace mcr
