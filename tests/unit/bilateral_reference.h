#pragma once
// The cross-bilateral filter's documented order-0 definition, in double with straight loops:
//   w(p,q) = exp(-|q-p|^2/(2 s^2)) prod_f exp(-|f(p)-f(q)|^2/(2 sigma_f^2))
// with the documented non-finite policy. The oracle of the bilateral tests, and the
// independent colour guide of the order=1 oracle.
#include <algorithm>
#include <cmath>
#include <vector>

#include "feature_filter_testutil.h"
#include "filters/image/bilateral.h"

namespace mcr::testutil {

inline Image bilateral_reference(const Frame& frame, const Params& given) {
  BilateralFilter probe;
  with_kernel_colour_weight(probe);
  for (const auto& [k, v] : given) probe.set(k, v);
  const ParamSet& ps = probe.params();
  const int w = frame.width, h = frame.height;
  const double ss = ps.get_float("spatial_sigma");
  const int fixed = int(ps.get_int("radius"));
  const int r = ss > 0 ? (fixed > 0 ? fixed : int(std::ceil(3 * ss - 1e-6))) : 0;
  const Image& colour = frame.image(Role::Colour);
  std::vector<OracleFeature> feats;
  if (ps.get_enum("use_colour") != "off") feats.push_back({&colour, 3, 1.0 / (2 * std::pow(ps.get_float("colour_sigma"), 2))});
  for (const OracleFeature& f : oracle_features(frame, ps)) feats.push_back(f);
  Image out(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s[3] = {0, 0, 0}, sw = 0;
      for (int qy = std::max(0, y - r); qy <= std::min(h - 1, y + r); ++qy)
        for (int qx = std::max(0, x - r); qx <= std::min(w - 1, x + r); ++qx) {
          const float* cq = colour.pixel(qx, qy);
          bool usable = finite_n(cq, 3);
          for (const OracleFeature& f : feats) usable = usable && finite_n(f.im->pixel(qx, qy), f.ch);
          if (!usable) continue;
          const double d2 = double(qx - x) * (qx - x) + double(qy - y) * (qy - y);
          double e = ss > 0 ? d2 / (2 * ss * ss) : 0.0;
          for (const OracleFeature& f : feats) {
            const float* a = f.im->pixel(x, y);
            const float* b = f.im->pixel(qx, qy);
            if (!finite_n(a, f.ch)) continue;  // own value not finite: this feature is skipped
            double dd = 0;
            for (int c = 0; c < f.ch; ++c) dd += (double(a[c]) - b[c]) * (double(a[c]) - b[c]);
            e += f.k * dd;
          }
          const double wq = std::exp(-e);
          for (int c = 0; c < 3; ++c) s[c] += wq * cq[c];
          sw += wq;
        }
      const float* cp = colour.pixel(x, y);
      for (int c = 0; c < 3; ++c)
        out.at(x, y, c) = float(sw > 0 ? s[c] / sw : (finite_n(cp, 3) ? cp[c] : 0.0));
    }
  return out;
}

}  // namespace mcr::testutil
