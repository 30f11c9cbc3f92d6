#include "prepare/albedo_prefilter.h"

#include <algorithm>
#include <cmath>

#include "filters/image/bilateral.h"
#include "util/parallel.h"

namespace mcr {

Image prefilter_albedo(const Frame& frame, const Pass& albedo, const AlbedoPrefilter& p, int nthreads) {
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
  f.passes.push_back(std::move(logp));
  for (Role r : {Role::Normal, Role::Position})
    if (const Pass* q = frame.find(r)) f.passes.push_back(*q);

  BilateralFilter bf;
  bf.set("order", std::int64_t(1));
  bf.set("spatial_sigma", 1.0);
  bf.set("colour_sigma", p.range_sigma);
  bf.set("normal_sigma", 0.5);
  bf.set("position_sigma", p.position_sigma);
  bf.set("use_albedo", std::string("off"));
  bf.set("ridge", 1e-3);  // a clean signal: slopes nearly free
  bf.commit();
  ExecOptions eo;
  eo.nthreads = nthreads;
  const Image smooth = bf.execute(f, eo);

  Image out = a;
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < ch; ++c) {
        const float v = a.at(x, y, c);
        if (!std::isfinite(v)) continue;
        // Channels beyond RGB (none in practice) keep their values.
        if (c < 3) out.at(x, y, c) = std::min(std::exp(smooth.at(x, y, c)), 3.4e38f);
      }
  });
  return out;
}

}  // namespace mcr
