// Rendering every pixel of a light field: one jitter per pixel from a hash (so a seed gives
// the same file on any thread count), rows in parallel.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>

#include "generator.h"
#include "util/error.h"
#include "util/parallel.h"

namespace mcr::lfgen {

void PixelSamples::reset(int spp) {
  value.assign(std::size_t(spp), Vec3());
  y1.assign(std::size_t(spp), 0.0);
  y2.assign(std::size_t(spp), 0.0);
  smin = smax = 0;
  has_slope = false;
  e1x = e1y = e2x = e2y = 0;
  depth = 0;
  p = n = w1 = w2 = mod = Vec3();
  u1.clear();
  u2.clear();
  texture.clear();
  dmin = dmax = 0;
  has_lens_slope = false;
}

namespace {
// Widens [lo, hi] by s (the first one, has false, sets both).
void widen(double s, bool& has, double& lo, double& hi) {
  lo = has ? std::min(lo, s) : s;
  hi = has ? std::max(hi, s) : s;
  has = true;
}
}  // namespace

void PixelSamples::add_slope(double s) { widen(s, has_slope, smin, smax); }

void PixelSamples::add_lens_slope(double s) { widen(s, has_lens_slope, dmin, dmax); }

double LightFieldGenerator::reference_weight(double y1, double y2) const {
  if (effect() == LightFieldEffect::Gi) return 1.0;
  const double s = sigma_y();
  return std::exp(-(y1 * y1 + y2 * y2) / (2 * s * s));
}

double LightFieldGenerator::sample_weight(const PixelSamples& ps, std::size_t k) const {
  const double w = reference_weight(ps.y1[k], ps.y2[k]);
  if (!has_lens()) return w;
  const double s = sigma_u();
  return w * std::exp(-(ps.u1[k] * ps.u1[k] + ps.u2[k] * ps.u2[k]) / (2 * s * s));
}

unsigned long long mix64(unsigned long long x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

void pixel_jitter(unsigned long long seed, unsigned salt, std::size_t pixel, double& j1, double& j2) {
  const unsigned long long h = mix64(mix64(seed ^ (0x5851f42d4c957f2dULL * (salt + 1))) + pixel);
  j1 = double(h >> 40) / double(1ULL << 24);  // 24 bits each: exact in float, in [0, 1)
  j2 = double((h >> 8) & 0xffffff) / double(1ULL << 24);
}

namespace {
// Pixel p's samples into lf: colours and coordinates.
void put_samples(const std::vector<Vec3>& colour, const std::vector<double>& y1, const std::vector<double>& y2,
                 std::size_t p, std::size_t spp, LightField& lf) {
  for (std::size_t k = 0; k < spp; ++k) {
    lf.r[p * spp + k] = float(colour[k].x);
    lf.g[p * spp + k] = float(colour[k].y);
    lf.b[p * spp + k] = float(colour[k].z);
    lf.y1[p * spp + k] = float(y1[k]);
    lf.y2[p * spp + k] = float(y2[k]);
  }
}
}  // namespace

void check_samples_per_axis(int l) {
  if (l < 1 || l > 64) throw Error(Errc::InvalidArgument, "light field: l = " + std::to_string(l) + " samples per axis, expected 1..64");
}

LightField render_lightfield(const LightFieldGenerator& gen, int l, unsigned long long seed, int nthreads,
                             const RowProgress& progress) {
  check_samples_per_axis(l);
  LightField lf;
  lf.resize(gen.width(), gen.height(), l, true);
  // Set after resize whatever it does with them (it is main's, core/image/lightfield.cpp).
  lf.width = gen.width();
  lf.height = gen.height();
  lf.l = l;
  lf.effect = gen.effect();
  lf.y_range = float(gen.y_range());
  lf.sigma_y = float(gen.sigma_y());
  const std::size_t spp = std::size_t(l) * std::size_t(l);
  if (lf.effect == LightFieldEffect::SoftShadows)
    for (auto* v : {&lf.mod_r, &lf.mod_g, &lf.mod_b}) v->assign(lf.pixels(), 0.f);
  std::shared_ptr<LightField> lens;
  if (gen.has_lens()) {
    lens = std::make_shared<LightField>();
    lens->resize(gen.width(), gen.height(), l, false);
    lens->effect = LightFieldEffect::Dof;
    lens->y_range = float(gen.u_range());
    lens->sigma_y = float(gen.sigma_u());
  }
  std::atomic<int> rows{0};
  std::mutex report;
  parallel_rows(0, gen.height(), nthreads, [&](int y) {
    PixelSamples ps;
    for (int x = 0; x < gen.width(); ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(gen.width()) + std::size_t(x);
      double j1 = 0, j2 = 0;
      pixel_jitter(seed, 0, p, j1, j2);
      ps.reset(int(spp));
      gen.render_pixel(x, y, l, j1, j2, ps);
      put_samples(ps.value, ps.y1, ps.y2, p, spp, lf);
      lf.smin[p] = float(ps.smin);
      lf.smax[p] = float(ps.smax);
      lf.e1x[p] = float(ps.e1x);
      lf.e1y[p] = float(ps.e1y);
      lf.e2x[p] = float(ps.e2x);
      lf.e2y[p] = float(ps.e2y);
      lf.depth[p] = float(ps.depth);
      lf.px[p] = float(ps.p.x);
      lf.py[p] = float(ps.p.y);
      lf.pz[p] = float(ps.p.z);
      lf.nx[p] = float(ps.n.x);
      lf.ny[p] = float(ps.n.y);
      lf.nz[p] = float(ps.n.z);
      if (lf.has_modulation()) lf.mod_r[p] = float(ps.mod.x), lf.mod_g[p] = float(ps.mod.y), lf.mod_b[p] = float(ps.mod.z);
      lf.w1x[p] = float(ps.w1.x), lf.w1y[p] = float(ps.w1.y), lf.w1z[p] = float(ps.w1.z);
      lf.w2x[p] = float(ps.w2.x), lf.w2y[p] = float(ps.w2.y), lf.w2z[p] = float(ps.w2.z);
      if (lens) {
        LightField& u = *lens;
        put_samples(ps.texture, ps.u1, ps.u2, p, spp, u);
        u.smin[p] = float(ps.dmin);
        u.smax[p] = float(ps.dmax);
        u.e1x[p] = 1;
        u.e2y[p] = 1;
        u.depth[p] = float(ps.depth);
      }
    }
    const int done = ++rows;
    if (progress) {
      const std::lock_guard<std::mutex> hold(report);
      progress(done);
    }
  });
  // Depth of field measures x in pixels: no world axes (the screen axes are exact).
  if (lf.effect == LightFieldEffect::Dof)
    for (auto* v : {&lf.w1x, &lf.w1y, &lf.w1z, &lf.w2x, &lf.w2y, &lf.w2z}) v->clear();
  lf.lens = lens;
  return lf;
}

}  // namespace mcr::lfgen
