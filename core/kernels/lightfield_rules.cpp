#include "kernels/lightfield_rules.h"

#include <algorithm>
#include <limits>

#include "util/error.h"

namespace mcr::lf {

namespace {

bool inside(const Roi& roi, std::size_t p, int w) { return roi.contains(int(p % std::size_t(w)), int(p / std::size_t(w))); }

float finite_or_zero(float v) { return std::isfinite(v) ? v : 0.0f; }

// Bounds after the soft-shadow smoothing (sec. 5): a pixel with lo == hi == 0 takes the
// smallest lo and largest hi of the pixels in its window whose bounds are not both 0.
void smoothed_bounds(const LightField& lf, int radius, int bounds_radius, std::vector<float>& lo, std::vector<float>& hi,
                     std::vector<unsigned char>& took) {
  const std::size_t n = lf.pixels();
  lo.resize(n);
  hi.resize(n);
  took.assign(n, 0);
  for (std::size_t p = 0; p < n; ++p) {
    const float a = finite_or_zero(lf.smin[p]), b = finite_or_zero(lf.smax[p]);
    lo[p] = std::min(a, b);
    hi[p] = std::max(a, b);
  }
  if (bounds_radius < 0) bounds_radius = lf.effect == LightFieldEffect::SoftShadows ? radius : 0;
  if (bounds_radius > 0) {
    // A pixel's few samples see part of what its neighbours see: the bounds of the window.
    const std::vector<float> lo0 = lo, hi0 = hi;
    const int w = lf.width, h = lf.height;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
        if (lo0[p] == 0 && hi0[p] == 0) continue;
        for (int yy = std::max(0, y - bounds_radius); yy <= std::min(h - 1, y + bounds_radius); ++yy)
          for (int xx = std::max(0, x - bounds_radius); xx <= std::min(w - 1, x + bounds_radius); ++xx) {
            const std::size_t q = std::size_t(yy) * std::size_t(w) + std::size_t(xx);
            if (lo0[q] == 0 && hi0[q] == 0) continue;
            lo[p] = std::min(lo[p], lo0[q]);
            hi[p] = std::max(hi[p], hi0[q]);
          }
      }
  }
  if (lf.effect != LightFieldEffect::SoftShadows || radius <= 0) return;
  const std::vector<float> lo0 = lo, hi0 = hi;
  const int w = lf.width, h = lf.height;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(w) + std::size_t(x);
      if (lo0[p] != 0 || hi0[p] != 0) continue;
      bool found = false;
      float a = 0, b = 0;
      for (int yy = std::max(0, y - radius); yy <= std::min(h - 1, y + radius); ++yy)
        for (int xx = std::max(0, x - radius); xx <= std::min(w - 1, x + radius); ++xx) {
          const std::size_t q = std::size_t(yy) * std::size_t(w) + std::size_t(xx);
          if (lo0[q] == 0 && hi0[q] == 0) continue;
          a = found ? std::min(a, lo0[q]) : lo0[q];
          b = found ? std::max(b, hi0[q]) : hi0[q];
          found = true;
        }
      if (found) {
        lo[p] = a;
        hi[p] = b;
        took[p] = 1;
      }
    }
}

// Radius along an axis of length len (pixels per x unit) for sigma (x units).
int radius_for(double sigma, float len, int cap) {
  const double spx = sigma * double(len);
  if (!(spx < 1e7)) return cap;
  return std::min(cap, int(std::ceil(2.0 * spx)));
}

float inv2s2(double sigma) {
  if (!(sigma > 0) || !std::isfinite(sigma)) return 0.0f;
  return float(std::min(1e30, 1.0 / (2.0 * sigma * sigma)));
}

}  // namespace

WeightY::WeightY(const LightField& lf) {
  box = lf.effect == LightFieldEffect::Gi;
  inv2sy2 = float(1.0 / (2.0 * double(lf.sigma_y) * double(lf.sigma_y)));
  range = lf.y_range;
}

std::vector<Rule> pixel_rules(const LightField& lf, const Options& o, Mode mode, const Roi& roi, Counts* counts) {
  if (!(lf.sigma_y > 0) || !std::isfinite(lf.sigma_y))
    throw Error(Errc::InvalidArgument, "light field: sigma_y must be a positive number, not " + std::to_string(lf.sigma_y));
  if (!(lf.y_range > 0) || !std::isfinite(lf.y_range))
    throw Error(Errc::InvalidArgument, "light field: y_range must be a positive number, not " + std::to_string(lf.y_range));
  const std::size_t ns = lf.samples(), np = lf.pixels();
  bool sized = lf.l >= 1 && lf.width >= 0 && lf.height >= 0;
  for (const std::vector<float>* v : {&lf.r, &lf.g, &lf.b, &lf.y1, &lf.y2}) sized = sized && v->size() == ns;
  for (const std::vector<float>* v : {&lf.smin, &lf.smax, &lf.e1x, &lf.e1y, &lf.e2x, &lf.e2y})
    sized = sized && v->size() == np;
  if (lf.has_geometry())
    for (const std::vector<float>* v : {&lf.px, &lf.py, &lf.pz, &lf.nx, &lf.ny, &lf.nz}) sized = sized && v->size() == np;
  if (!sized) throw Error(Errc::Internal, "light field: arrays not sized for " + std::to_string(lf.width) + "x" +
                                              std::to_string(lf.height) + " pixels of " + std::to_string(lf.l) +
                                              "x" + std::to_string(lf.l) + " samples");
  std::vector<float> lo, hi;
  std::vector<unsigned char> took;
  smoothed_bounds(lf, o.smooth_radius, o.bounds_radius, lo, hi, took);
  const std::size_t n = lf.pixels();
  const int cap = std::max(0, o.max_width / 2);
  const double sy = lf.sigma_y;
  const double mu = o.mu > 0 ? o.mu : 1.0;
  Counts c;
  std::vector<Rule> rules(n);
  for (std::size_t p = 0; p < n; ++p) {
    Rule& r = rules[p];
    const bool in = inside(roi, p, lf.width);
    if (in) c.smoothed += took[p];
    const double a = lo[p], b = hi[p];
    double sigma = 0;
    r.kind = Kind::Own;
    if (a == 0 && b == 0) {
      if (in) ++c.own;
    } else if (mode == Mode::Sheared && a * b > 0) {
      r.kind = Kind::Sheared;
      r.eta = float(0.5 * (1.0 / a + 1.0 / b));
      sigma = b > a ? sy * a * b / (b - a) : std::numeric_limits<double>::infinity();
    } else {
      if (mode == Mode::Sheared && in) ++c.fallback;
      if (mode == Mode::AxisAligned || o.fallback_aaf) {
        r.kind = Kind::AxisAligned;
        sigma = sy * std::min(std::fabs(a), std::fabs(b)) / (2.0 * mu);
      }
    }
    const float e1x = lf.e1x[p], e1y = lf.e1y[p], e2x = lf.e2x[p], e2y = lf.e2y[p];
    r.len1 = std::sqrt(e1x * e1x + e1y * e1y);
    r.len2 = std::sqrt(e2x * e2x + e2y * e2y);
    if (r.kind != Kind::Own) {
      const float det = e1x * e2y - e1y * e2x;
      const bool degenerate = !(r.len1 > 1e-6f) || !(r.len2 > 1e-6f) || !std::isfinite(det) ||
                              !(std::fabs(det) > 1e-4f * r.len1 * r.len2);
      if (degenerate) {
        r.kind = Kind::Own;
        r.eta = 0;
        if (in) ++c.degenerate;
      }
    }
    if (r.kind == Kind::Own) {
      r.own_output = true;
      continue;
    }
    r.inv2sx2 = inv2s2(sigma);
    r.r1 = radius_for(sigma, r.len1, cap);
    r.r2 = radius_for(sigma, r.len2, cap);
    r.own_output = lightfield_converged(lf, p);
    if (r.own_output && in) ++c.converged;
  }
  c.pixels = std::size_t(std::max(0, roi.width())) * std::size_t(std::max(0, roi.height()));
  if (counts) *counts = c;
  return rules;
}

void own_mean(const LightField& lf, const WeightY& wy, std::size_t p, float* rgb) {
  const std::size_t k0 = p * std::size_t(lf.spp()), k1 = k0 + std::size_t(lf.spp());
  double s[3] = {0, 0, 0}, t[3] = {0, 0, 0}, ws = 0;
  for (std::size_t k = k0; k < k1; ++k) {
    const double w = double(wy(lf.y1[k])) * double(wy(lf.y2[k]));
    s[0] += w * lf.r[k];
    s[1] += w * lf.g[k];
    s[2] += w * lf.b[k];
    t[0] += lf.r[k];
    t[1] += lf.g[k];
    t[2] += lf.b[k];
    ws += w;
  }
  const double cnt = double(k1 - k0);
  for (int c = 0; c < 3; ++c) {
    const double v = ws > 0 ? s[c] / ws : (cnt > 0 ? t[c] / cnt : 0.0);
    rgb[c] = std::isfinite(v) ? float(v) : 0.0f;
  }
}

Rejection::Rejection(const LightField& lf, const Options& o) : lf_(&lf) {
  active_ = o.reject && lf.has_geometry() && lf.effect != LightFieldEffect::Dof;
  cos_max_ = float(std::cos(double(o.normal_degrees) * 3.14159265358979323846 / 180.0));
}

bool Rejection::rejects(std::size_t p, std::size_t q, float dist, float pixel_world) const {
  if (!active_ || p == q) return false;
  const LightField& lf = *lf_;
  const float dot = lf.nx[p] * lf.nx[q] + lf.ny[p] * lf.ny[q] + lf.nz[p] * lf.nz[q];
  const float np = lf.nx[p] * lf.nx[p] + lf.ny[p] * lf.ny[p] + lf.nz[p] * lf.nz[p];
  const float nq = lf.nx[q] * lf.nx[q] + lf.ny[q] * lf.ny[q] + lf.nz[q] * lf.nz[q];
  if (np > 0 && nq > 0 && dot < cos_max_ * std::sqrt(np * nq)) return true;
  const float dx = lf.px[q] - lf.px[p], dy = lf.py[q] - lf.py[p], dz = lf.pz[q] - lf.pz[p];
  const float gap = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (gap > 2.0f * dist + pixel_world) return true;
  // Off P's tangent plane: another receiver (a box's top seen beside the ground at the same
  // screen distance) shears along other lines. A pixel's size plus a tenth of the gap allows a
  // gently curved receiver.
  if (np > 0) {
    const float off = std::fabs(dx * lf.nx[p] + dy * lf.ny[p] + dz * lf.nz[p]) / std::sqrt(np);
    if (off > pixel_world + 0.1f * gap) return true;
  }
  return false;
}

std::string counts_note(const std::string& who, const Counts& c, bool sheared) {
  std::string s = who + ": " + std::to_string(c.own) + " of " + std::to_string(c.pixels) + " pixels had nothing to " +
                  (sheared ? "shear" : "filter") + " (own samples)";
  if (sheared) s += ", " + std::to_string(c.fallback) + " axis-aligned fallback";
  if (c.converged) s += ", " + std::to_string(c.converged) + " converged (own samples)";
  if (c.degenerate) s += ", " + std::to_string(c.degenerate) + " with degenerate axes (own samples)";
  if (c.zero_weight) s += ", " + std::to_string(c.zero_weight) + " with every weight 0 (own samples)";
  if (c.smoothed) s += ", " + std::to_string(c.smoothed) + " took smoothed slope bounds";
  return s;
}

}  // namespace mcr::lf
