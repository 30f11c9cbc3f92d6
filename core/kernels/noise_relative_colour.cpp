#include "kernels/noise_relative_colour.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "image/luminance.h"
#include "kernels/cross_bilateral.h"
#include "kernels/feature_guides.h"
#include "kernels/noise_variance.h"
#include "kernels/planes.h"
#include "util/parallel.h"

namespace mcr {

ParamSpec colour_weight_param() {
  return ParamSpec::Enum("colour_weight", "absolute", {"absolute", "noise"},
                         "units of colour_sigma: absolute = radiance (after demodulation); noise = the centre pixel's "
                         "estimated noise standard deviation (variance from 3x3 high-pass residuals, smoothed 3x3; "
                         "SVGF-style), so one sigma suits dark and bright regions and any noise level");
}

std::vector<double> noise_variance(const Image& colour, const Image* sample_count, const Roi& box, int nthreads) {
  const int w = colour.width(), h = colour.height();
  std::vector<double> out(std::size_t(std::max(0, box.width())) * std::size_t(std::max(0, box.height())), 0.0);
  if (box.empty()) return out;
  // The 3x3 smoothing reads one pixel beyond the box; the estimate's own 3x3 window is
  // handled inside estimate_variance (it reads what it needs around its region).
  const Roi er = box.grown(1, w, h);
  std::vector<std::uint8_t> valid(std::size_t(w) * std::size_t(h), 1);
  const Roi vr = er.grown(2, w, h);
  parallel_rows(vr.y0, vr.y1, nthreads, [&](int y) {
    for (int x = vr.x0; x < vr.x1; ++x) {
      const float* p = colour.pixel(x, y);
      valid[std::size_t(y) * w + x] = finite3(p);
    }
  });
  const std::vector<double> v = estimate_variance(colour, valid, sample_count, 1, er, nthreads);
  static constexpr double kb[3] = {0.25, 0.5, 0.25};
  parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
    for (int x = box.x0; x < box.x1; ++x) {
      double s = 0, sw = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < er.x0 || xx >= er.x1 || yy < er.y0 || yy >= er.y1) continue;
          const std::size_t j = std::size_t(yy) * w + xx;
          if (!valid[j]) continue;
          const double wt = kb[dx + 1] * kb[dy + 1];
          s += wt * std::min(v[j], 1e300);
          sw += wt;
        }
      const float* p = colour.pixel(x, y);
      const bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
      const double yl = finite ? luminance(p) : 0.0;
      const double gv = sw > 0 ? s / sw : 0.0;
      out[std::size_t(y - box.y0) * std::size_t(box.width()) + std::size_t(x - box.x0)] =
          std::min(3.0 * gv + 1e-6 * yl * yl + 1e-30, 1e300);
    }
  });
  return out;
}

void noise_relative_colour_a(const Image& colour, const Image* sample_count, const Guides& g, int nthreads,
                             std::vector<float>& a) {
  const PlaneBox& pb = g.pb;
  const Roi& box = pb.box;
  pb.prepare(a);
  const std::vector<double> s2 = noise_variance(colour, sample_count, box, nthreads);
  const int bw = box.width();
  parallel_rows(box.y0, box.y1, nthreads, [&](int y) {
    for (int x = box.x0; x < box.x1; ++x) {
      const std::size_t i = pb.index(x, y);
      const double a0 = g.colour_a.empty() ? double(g.colour_a_const) : double(g.colour_a[i]);
      const double v = a0 / std::sqrt(s2[std::size_t(y - box.y0) * std::size_t(bw) + std::size_t(x - box.x0)]);
      a[i] = float(std::clamp(v, 0.0, 1e18));
    }
  });
}

void set_colour_weight(CrossPass& pass, const Guides& guides, const ParamSet& params, const Frame& frame,
                       const Image& colour, int nthreads, std::vector<float>& scratch) {
  pass.colour_weight = guides.colour;
  pass.colour_a = guides.colour_a.empty() ? nullptr : guides.colour_a.data();
  pass.colour_a_const = guides.colour_a_const;
  if (guides.colour && params.get_enum("colour_weight") == "noise") {
    const Pass* spp = frame.find(Role::SampleCount);
    noise_relative_colour_a(colour, spp ? &spp->image : nullptr, guides, nthreads, scratch);
    pass.colour_a = scratch.data();
  }
}

}  // namespace mcr
