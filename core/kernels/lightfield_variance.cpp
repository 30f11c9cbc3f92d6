#include "kernels/lightfield_variance.h"

#include <algorithm>
#include <cmath>

#include "util/parallel.h"

namespace mcr::lf {

namespace {

int stratum(float y, float range, int l) {
  const int i = int(std::floor((double(y) + range) / (2.0 * range) * l));
  return std::min(std::max(i, 0), l - 1);
}

}  // namespace

Image estimate_variance(const LightField& lf, VarianceFrom from, const Roi& roi, int nthreads) {
  Image var(lf.width, lf.height, 3, -1.0f);
  const int n = lf.spp();
  if (n < 2) return var;
  const std::vector<float>* v[3] = {&lf.r, &lf.g, &lf.b};
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      const std::size_t k0 = p * std::size_t(n), k1 = k0 + std::size_t(n);
      for (int c = 0; c < 3; ++c) {
        const std::vector<float>& f = *v[c];
        double out = 0;
        if (from == VarianceFrom::Strata) {
          double s[2] = {0, 0}, w[2] = {0, 0};
          for (std::size_t k = k0; k < k1; ++k) {
            const double wk = double(lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y1[k])) *
                              lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y2[k]);
            const int h = (stratum(lf.y1[k], lf.y_range, lf.l) + stratum(lf.y2[k], lf.y_range, lf.l)) & 1;
            s[h] += wk * f[k], w[h] += wk;
          }
          if (w[0] > 0 && w[1] > 0) {
            const double d = s[0] / w[0] - s[1] / w[1];
            out = d * d / 4.0;
          }
        } else {
          double sw = 0, swf = 0;
          for (std::size_t k = k0; k < k1; ++k) {
            const double wk = double(lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y1[k])) *
                              lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y2[k]);
            sw += wk, swf += wk * f[k];
          }
          if (sw > 0) {
            const double mean = swf / sw;
            double s2 = 0;
            for (std::size_t k = k0; k < k1; ++k) {
              const double wk = double(lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y1[k])) *
                                lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y2[k]);
              s2 += wk * wk * (f[k] - mean) * (f[k] - mean);
            }
            out = s2 / (sw * sw) * double(n) / double(n - 1);
          }
        }
        var.at(x, y, c) = float(std::min(out, 3.0e38));
      }
    }
  });
  return var;
}

}  // namespace mcr::lf
