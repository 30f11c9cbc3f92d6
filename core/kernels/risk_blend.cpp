#include "kernels/risk_blend.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "kernels/window_sums.h"
#include "util/parallel.h"

namespace mcr {

double blend_by_risk(const Image& input, const Image& variance, const Roi& roi, int radius, int nthreads, Image& out) {
  const int w = roi.width(), h = roi.height();
  if (w <= 0 || h <= 0) return 1.0;
  WindowSums var(w, h, false), dev(w, h, false);
  // Pixels whose variance is known and whose values are finite: the only ones weighed or blended.
  std::vector<std::uint8_t> usable(std::size_t(w) * std::size_t(h), 0);
  auto at = [&](int x, int y) { return std::size_t(y - roi.y0) * std::size_t(w) + std::size_t(x - roi.x0); };
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      bool ok = true;
      for (int c = 0; c < 3 && ok; ++c)
        ok = variance.at(x, y, c) >= 0 && std::isfinite(variance.at(x, y, c)) && std::isfinite(input.at(x, y, c)) &&
             std::isfinite(out.at(x, y, c));
      if (!ok) continue;
      usable[at(x, y)] = 1;
      double sv = 0, sd = 0;
      for (int c = 0; c < 3; ++c) {
        const double f = out.at(x, y, c), d = f - double(input.at(x, y, c));
        const double wt = 1.0 / (f * f + 0.01);
        sv += wt * double(variance.at(x, y, c));
        sd += wt * d * d;
      }
      var.set(x - roi.x0, y - roi.y0, std::min(sv, 1e300));
      dev.set(x - roi.x0, y - roi.y0, std::min(sd, 1e300));
    }
  });
  var.sum_windows(radius, nthreads);
  dev.sum_windows(radius, nthreads);
  std::vector<double> row_sum(std::size_t(h), 0.0);
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    double s = 0;
    for (int x = roi.x0; x < roi.x1; ++x) {
      const double v = var.value(x - roi.x0, y - roi.y0), d = dev.value(x - roi.x0, y - roi.y0);
      const double a = d > v ? v / d : 1.0;
      s += a;
      if (a >= 1.0 || !usable[at(x, y)]) continue;
      for (int c = 0; c < 3; ++c) {
        const double yv = input.at(x, y, c);
        out.at(x, y, c) = float(yv + a * (double(out.at(x, y, c)) - yv));
      }
    }
    row_sum[std::size_t(y - roi.y0)] = s;
  });
  double s = 0;
  for (double r : row_sum) s += r;
  return s / (double(w) * double(h));
}

}  // namespace mcr
