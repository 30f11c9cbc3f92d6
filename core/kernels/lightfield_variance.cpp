#include "kernels/lightfield_variance.h"

#include <algorithm>
#include <cmath>
#include <vector>

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
    // Per pixel, each sample's weight and half once (not per channel).
    std::vector<double> w(static_cast<std::size_t>(n));
    std::vector<unsigned char> half(static_cast<std::size_t>(n));
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      const std::size_t k0 = p * std::size_t(n);
      double sw = 0;
      for (int j = 0; j < n; ++j) {
        const std::size_t k = k0 + std::size_t(j);
        w[std::size_t(j)] = lightfield_sample_weight(lf, k);
        half[std::size_t(j)] =
            (stratum(lf.y1[k], lf.y_range, lf.l) + stratum(lf.y2[k], lf.y_range, lf.l)) & 1;
        sw += w[std::size_t(j)];
      }
      for (int c = 0; c < 3; ++c) {
        const float* f = v[c]->data() + k0;
        double out = 0;
        if (from == VarianceFrom::Strata) {
          double s[2] = {0, 0}, ws[2] = {0, 0};
          for (int j = 0; j < n; ++j) {
            s[half[std::size_t(j)]] += w[std::size_t(j)] * f[j];
            ws[half[std::size_t(j)]] += w[std::size_t(j)];
          }
          if (ws[0] > 0 && ws[1] > 0) {
            const double d = s[0] / ws[0] - s[1] / ws[1];
            out = d * d / 4.0;
          }
        } else if (sw > 0) {
          double swf = 0;
          for (int j = 0; j < n; ++j) swf += w[std::size_t(j)] * f[j];
          const double mean = swf / sw;
          double s2 = 0;
          for (int j = 0; j < n; ++j) s2 += w[std::size_t(j)] * w[std::size_t(j)] * (f[j] - mean) * (f[j] - mean);
          out = s2 / (sw * sw) * double(n) / double(n - 1);
        }
        var.at(x, y, c) = float(std::min(out, 3.0e38));
      }
    }
  });
  return var;
}

}  // namespace mcr::lf
