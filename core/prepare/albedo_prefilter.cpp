#include "prepare/albedo_prefilter.h"

#include <algorithm>
#include <cmath>

#include "kernels/cross_bilateral_fit.h"
#include "util/parallel.h"

namespace mcr {

Image prefilter_albedo(const Frame& frame, const Pass& albedo, const AlbedoPrefilter& p, const Roi& roi, int nthreads) {
  const Image& a = albedo.image;
  const int w = a.width(), h = a.height(), ch = a.channels();
  Frame f;
  f.width = w;
  f.height = h;
  f.path = frame.path;
  Pass logp;
  logp.role = Role::Colour;
  logp.name = albedo.name + " (log)";
  logp.image = Image(w, h, 3);
  const float lo = float(p.floor);
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = a.at(x, y, std::min(c, ch - 1));
        // Non-finite stays non-finite: the bilateral leaves it out of every window.
        logp.image.at(x, y, c) = std::isfinite(v) ? std::log(std::max(v, lo)) : v;
      }
  });
  const Image logp_copy = logp.image;
  f.passes.push_back(std::move(logp));
  for (Role r : {Role::Normal, Role::Position})
    if (const Pass* q = frame.find(r)) f.passes.push_back(*q);

  // The cross-bilateral kernel of order 1 with a fixed setting: normal and position
  // weights, colour (the log albedo itself) as range, a 1-px spatial Gaussian.
  static const ParamTable table = cross_bilateral_fit_params();
  ParamSet ps("albedo_prefilter", &table);
  ps.set("order", std::int64_t(1));
  ps.set("spatial_sigma", 1.0);
  ps.set("colour_sigma", p.range_sigma);
  ps.set("normal_sigma", 0.5);
  ps.set("position_sigma", p.position_sigma);
  ps.set("use_albedo", std::string("off"));
  ps.set("ridge", 1e-3);  // a clean signal: slopes nearly free
  Image smooth = logp_copy;
  CrossBilateralScratch scratch;
  cross_bilateral_fit(f, f.passes.front().image, ps, "albedo_prefilter", roi, smooth, nthreads, [](std::string) {}, scratch);

  Image out = a;
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    for (int x = roi.x0; x < roi.x1; ++x)
      for (int c = 0; c < ch; ++c) {
        const float v = a.at(x, y, c);
        if (!std::isfinite(v)) continue;
        // Channels beyond RGB (none in practice) keep their values.
        if (c >= 3) continue;
        const float l = smooth.at(x, y, c);
        out.at(x, y, c) = std::isfinite(l) ? std::min(std::exp(l), 3.4e38f) : 1.0f;
      }
  });
  return out;
}

}  // namespace mcr
