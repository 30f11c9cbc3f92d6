#include "kernels/noise_scale.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kernels/albedo_divisor.h"
#include "kernels/window_sums.h"
#include "util/parallel.h"

namespace mcr {

namespace {

constexpr int kVarianceRadius = 3;
constexpr int kTile = 8, kTileGrow = 4;
constexpr double kRelativeEps = 1e-3;  // luminance^2 below which noise counts as absolute
constexpr double kChi2MedianToMean = 1.27;
constexpr double kFloorRelative = 0.02;
constexpr double kRareOutliers = 0.03;  // share of a tile's pixels

// The frame's RGB at (x, y) and whether it is finite.
struct Rgb {
  const Image& img;
  bool finite(int x, int y) const {
    const float* p = img.pixel(x, y);
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
  }
  const float* at(int x, int y) const { return img.pixel(x, y); }
};

// The median of 9 values by a fixed network of min/max exchanges (no branches).
inline float median9(float* p) {
  auto op = [p](int a, int b) {
    const float lo = std::min(p[a], p[b]), hi = std::max(p[a], p[b]);
    p[a] = lo;
    p[b] = hi;
  };
  op(1, 2); op(4, 5); op(7, 8); op(0, 1); op(3, 4); op(6, 7); op(1, 2); op(4, 5); op(7, 8);
  op(0, 3); op(5, 8); op(4, 7); op(3, 6); op(1, 4); op(2, 5); op(4, 7); op(4, 2); op(6, 4); op(4, 2);
  return p[4];
}

float median_of(float* v, int n) {
  if (n == 9) return median9(v);
  std::nth_element(v, v + n / 2, v + n);
  const float hi = v[n / 2];
  if (n % 2) return hi;
  return 0.5f * *std::max_element(v, v + n / 2) + 0.5f * hi;  // halves first: no overflow near FLT_MAX
}

double luminance2(const float* m) { return (double(m[0]) * m[0] + double(m[1]) * m[1] + double(m[2]) * m[2]) / 3.0; }
double luminance2(const double* m) { return (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]) / 3.0; }

// The per-channel range [lo, hi] of the 8 neighbours of (x, y) that ok() accepts; false
// (lo = hi = the pixel) when there is none.
template <class Ok>
bool neighbour_range(const Rgb& y, const Ok& ok, int x, int yy, float lo[3], float hi[3]) {
  const float* p = y.at(x, yy);
  for (int c = 0; c < 3; ++c) lo[c] = hi[c] = p[c];
  bool any = false;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int qx = x + dx, qy = yy + dy;
      if ((!dx && !dy) || !ok(qx, qy)) continue;
      const float* q = y.at(qx, qy);
      for (int c = 0; c < 3; ++c) {
        lo[c] = any ? std::min(lo[c], q[c]) : q[c];
        hi[c] = any ? std::max(hi[c], q[c]) : q[c];
      }
      any = true;
    }
  return any;
}

// A variance pass at (x, y): the mean over its (at most 3) channels, or -1 where one is not
// finite and >= 0.
double pass_variance(const Image& v, int x, int y) {
  const float* p = v.pixel(x, y);
  const int vc = std::min(3, v.channels());
  double sum = 0;
  for (int c = 0; c < vc; ++c) {
    if (!(std::isfinite(p[c]) && p[c] >= 0.0f)) return -1.0;
    sum += p[c];
  }
  return sum / vc;
}

}  // namespace

bool stands_out_in_own_samples(const Image& colour, const Image& variance, int x, int y) {
  const Rgb rgb{colour};
  const double own = pass_variance(variance, x, y);
  if (own < 0 || !rgb.finite(x, y)) return false;
  const float* p = rgb.at(x, y);
  float lo[3], hi[3];
  const auto ok = [&](int qx, int qy) {
    return qx >= 0 && qy >= 0 && qx < colour.width() && qy < colour.height() && rgb.finite(qx, qy);
  };
  if (!neighbour_range(rgb, ok, x, y, lo, hi)) return false;
  double d2 = 0;
  for (int c = 0; c < 3; ++c) {
    const double out = double(p[c]) - std::min(std::max(p[c], lo[c]), hi[c]);
    d2 += out * out;
  }
  return d2 / 3.0 > kOutlierSigmas * kOutlierSigmas * own;
}

std::vector<std::uint8_t> detail_mask(const Image& colour, const Image* variance, const Roi& region, int nthreads) {
  const int w = colour.width(), h = colour.height();
  std::vector<std::uint8_t> mask;
  if (!variance || variance->width() != w || variance->height() != h) return mask;
  mask.assign(std::size_t(w) * std::size_t(h), 0);
  const Roi r = region.clipped(w, h);
  parallel_rows(r.y0, r.y1, nthreads, [&](int y) {
    for (int x = r.x0; x < r.x1; ++x) mask[std::size_t(y) * std::size_t(w) + std::size_t(x)] = stands_out_in_own_samples(colour, *variance, x, y);
  });
  return mask;
}

double NoiseScales::robust(std::size_t i, int c) const {
  const double m = median[i * 3 + std::size_t(c)];
  return std::min(std::max(double(relative[i]) * (m * m + kRelativeEps), kFloorRelative * kFloorRelative * m * m), 3.0e38);
}

double NoiseScales::variance_of(std::size_t i, int c) const {
  if (albedo.empty()) {
    const double m = median[i * 3 + std::size_t(c)];
    return double(variance[i]) * (m * m + kRelativeEps) / (luminance2(&median[i * 3]) + kRelativeEps);
  }
  // The illumination's variance shared among the channels as its median (the colour's over the
  // pixel's albedo) is, then scaled back by the albedo^2.
  // In double: a median near FLT_MAX over an albedo of 0.01 overflows a float (inf / inf).
  double flat[3];
  for (int k = 0; k < 3; ++k) flat[k] = double(median[i * 3 + std::size_t(k)]) / albedo[i * 3 + std::size_t(k)];
  const double a = albedo[i * 3 + std::size_t(c)], m = flat[c];
  return double(variance[i]) * (m * m + kRelativeEps) / (luminance2(flat) + kRelativeEps) * a * a;
}

NoiseScales estimate_noise_scales(const Image& colour, const Roi& box_in, int nthreads, const Image* vpass,
                                  const Image* modulation) {
  const int W = colour.width(), H = colour.height();
  NoiseScales s;
  s.box = box_in.clipped(W, H);
  if (s.box.empty()) return s;
  const Rgb y{colour};
  const bool use_pass = vpass && vpass->width() == W && vpass->height() == H && vpass->channels() > 0;
  auto pass_at = [&](int x, int yy) { return pass_variance(*vpass, x, yy); };
  const bool demod = !use_pass && modulation && modulation->width() == W && modulation->height() == H &&
                     modulation->channels() >= 3;
  // The floor but not the demodulation's ceiling: an emitter's Denoising Albedo is its emission
  // (a screen's picture, up to 2.7), which capped at 1 would stay in the illumination and read as
  // noise, so the step back trusted a blur of a noise-free emitter (studio 64 spp, pwaf: 0.0055
  // against 0.0042 uncapped). Only the estimate divides so; the filters' demodulation keeps it.
  auto albedo_at = [&](int x, int yy, int c) {
    return demodulation_albedo(modulation->pixel(x, yy)[c], float(kDefaultAlbedoFloor), std::numeric_limits<float>::max());
  };
  // The value the variance's products read: the colour, or the illumination.
  auto value = [&](const float* p, int x, int yy, int c) {
    return demod ? double(p[c]) / albedo_at(x, yy, c) : double(p[c]);
  };
  const std::size_t n = std::size_t(s.box.width()) * std::size_t(s.box.height());
  s.variance.assign(n, 0.0f);
  s.relative.assign(n, 0.0f);
  s.median.assign(n * 3, 0.0f);
  s.finite.assign(n, 0);
  s.outlier.assign(n, 0);
  s.excess.assign(n, 0.0f);
  s.detail.assign(n, 0);
  if (demod) s.albedo.assign(n * 3, 1.0f);

  // Region T: the tiles' windows. Medians and residual energies are needed there.
  const Roi T = s.box.grown(kTileGrow + kTile, W, H);
  // Which pixels are finite, over T and the ring every neighbourhood reads around it.
  const Roi F = T.grown(std::max(2, kVarianceRadius + 1), W, H);
  std::vector<std::uint8_t> fin(std::size_t(F.width()) * std::size_t(F.height()), 0);
  parallel_rows(F.y0, F.y1, nthreads, [&](int yy) {
    for (int x = F.x0; x < F.x1; ++x) fin[std::size_t(yy - F.y0) * std::size_t(F.width()) + std::size_t(x - F.x0)] = y.finite(x, yy);
  });
  auto ok = [&](int x, int yy) {
    return x >= F.x0 && yy >= F.y0 && x < F.x1 && yy < F.y1 &&
           fin[std::size_t(yy - F.y0) * std::size_t(F.width()) + std::size_t(x - F.x0)];
  };
  const int tw = T.width(), th = T.height();
  std::vector<float> med(std::size_t(tw) * std::size_t(th) * 3, 0.0f);
  std::vector<float> erel(std::size_t(tw) * std::size_t(th), 0.0f);
  std::vector<std::uint8_t> eok(std::size_t(tw) * std::size_t(th), 0);
  parallel_rows(T.y0, T.y1, nthreads, [&](int yy) {
    float vals[3][9];
    for (int x = T.x0; x < T.x1; ++x) {
      const std::size_t i = std::size_t(yy - T.y0) * std::size_t(tw) + std::size_t(x - T.x0);
      if (!ok(x, yy)) continue;
      int k = 0;
      double nb[3] = {0, 0, 0};
      int nn = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int qx = x + dx, qy = yy + dy;
          if (!ok(qx, qy)) continue;
          const float* q = y.at(qx, qy);
          for (int c = 0; c < 3; ++c) vals[c][k] = q[c];
          ++k;
          if (dx || dy) {
            for (int c = 0; c < 3; ++c) nb[c] += q[c];
            ++nn;
          }
        }
      double my2 = 0;
      for (int c = 0; c < 3; ++c) {
        const float m = median_of(vals[c], k);
        med[i * 3 + std::size_t(c)] = m;
        my2 += double(m) * m;
      }
      my2 /= 3.0;
      if (nn == 0) continue;
      const float* p = y.at(x, yy);
      double e = 0;
      for (int c = 0; c < 3; ++c) {
        const double r = double(p[c]) - nb[c] / nn;
        e += r * r;
      }
      // Var(y - mean of nn neighbours) = s^2 (1 + 1/nn).
      erel[i] = float(std::min(e / 3.0 / (1.0 + 1.0 / nn) / (my2 + kRelativeEps), 3.0e38));
      eok[i] = 1;
    }
  });

  // Robust scale per tile of the box: the median relative residual of the tile's window.
  // The tiles lie on the frame's grid (multiples of kTile from 0), whatever the box: a band of
  // a frame (pipeline/tiled_run.h) sees the tiles the whole frame does.
  const int gx0 = s.box.x0 - s.box.x0 % kTile, gy0 = s.box.y0 - s.box.y0 % kTile;
  const int ntx = (s.box.x1 - gx0 + kTile - 1) / kTile, nty = (s.box.y1 - gy0 + kTile - 1) / kTile;
  std::vector<float> tile_rel(std::size_t(ntx) * std::size_t(nty), 0.0f);
  parallel_rows(0, nty, nthreads, [&](int ty) {
    std::vector<float> buf;
    for (int tx = 0; tx < ntx; ++tx) {
      const int x0 = gx0 + tx * kTile, y0 = gy0 + ty * kTile;
      const Roi win = Roi{x0, y0, x0 + kTile, y0 + kTile}.grown(kTileGrow, W, H);
      buf.clear();
      for (int yy = win.y0; yy < win.y1; ++yy)
        for (int x = win.x0; x < win.x1; ++x) {
          const std::size_t i = std::size_t(yy - T.y0) * std::size_t(tw) + std::size_t(x - T.x0);
          if (eok[i]) buf.push_back(erel[i]);
        }
      tile_rel[std::size_t(ty) * std::size_t(ntx) + std::size_t(tx)] =
          buf.empty() ? 0.0f : float(kChi2MedianToMean) * median_of(buf.data(), int(buf.size()));
    }
  });

  // The excess of every pixel the variance reads (a firefly's own), before the variance:
  // a firefly takes no part in it, or its one sample would spread its energy over the
  // window of every pixel near it (the step back and auto treat it by itself).
  const Roi E = s.box.grown(kVarianceRadius + 1, W, H);
  std::vector<float> exc(std::size_t(E.width()) * std::size_t(E.height()), 0.0f);
  // The same above the range only: an outlier must be brighter than its neighbours (.h).
  std::vector<std::uint8_t> above(exc.size(), 0);
  auto tile_of = [&](int x, int yy) {
    const int tx = std::min(std::max((x - gx0) / kTile, 0), ntx - 1);
    const int ty = std::min(std::max((yy - gy0) / kTile, 0), nty - 1);
    return tile_rel[std::size_t(ty) * std::size_t(ntx) + std::size_t(tx)];
  };
  parallel_rows(E.y0, E.y1, nthreads, [&](int yy) {
    for (int x = E.x0; x < E.x1; ++x) {
      if (!ok(x, yy)) continue;
      const std::size_t i = std::size_t(yy - T.y0) * std::size_t(tw) + std::size_t(x - T.x0);
      const float* p = y.at(x, yy);
      float lo[3], hi[3];
      const bool any = neighbour_range(y, ok, x, yy, lo, hi);
      const double rel = tile_of(x, yy);
      double dev = 0, up = 0;
      for (int c = 0; c < 3; ++c) {
        const double m = med[i * 3 + std::size_t(c)];
        const double robust = std::min(std::max(rel * (m * m + kRelativeEps), kFloorRelative * kFloorRelative * m * m), 3.0e38);
        const double out = any ? double(p[c]) - std::min(std::max(p[c], lo[c]), hi[c]) : 0.0;
        dev += out * out / std::max(robust, 1e-30);
        if (out > 0) up += out * out / std::max(robust, 1e-30);
      }
      const std::size_t e = std::size_t(yy - E.y0) * std::size_t(E.width()) + std::size_t(x - E.x0);
      exc[e] = float(std::min(dev / 3.0, 3.0e38));
      above[e] = up / 3.0 > kOutlierSigmas * kOutlierSigmas;
    }
  });
  // Where outliers are many (a 1-spp render lit by rare paths), they are the noise itself and
  // stay in: only a tile (8x8, grown by 4) whose outliers are under kRareOutliers of its
  // pixels leaves them out.
  std::vector<std::uint8_t> rare(std::size_t(ntx) * std::size_t(nty), 0);
  parallel_rows(0, nty, nthreads, [&](int ty) {
    for (int tx = 0; tx < ntx; ++tx) {
      const int x0 = gx0 + tx * kTile, y0 = gy0 + ty * kTile;
      const Roi win = Roi{x0, y0, x0 + kTile, y0 + kTile}.grown(kTileGrow, W, H);
      int n = 0, out = 0;
      for (int yy = std::max(win.y0, E.y0); yy < std::min(win.y1, E.y1); ++yy)
        for (int x = std::max(win.x0, E.x0); x < std::min(win.x1, E.x1); ++x) {
          if (!ok(x, yy)) continue;
          ++n;
          out += exc[std::size_t(yy - E.y0) * std::size_t(E.width()) + std::size_t(x - E.x0)] > kOutlierSigmas * kOutlierSigmas;
        }
      rare[std::size_t(ty) * std::size_t(ntx) + std::size_t(tx)] = out <= kRareOutliers * n;
    }
  });
  auto calm = [&](int x, int yy) {  // finite, and not a rare outlier
    if (!ok(x, yy)) return false;
    if (exc[std::size_t(yy - E.y0) * std::size_t(E.width()) + std::size_t(x - E.x0)] <= kOutlierSigmas * kOutlierSigmas)
      return true;
    const int tx = std::min(std::max((x - gx0) / kTile, 0), ntx - 1);
    const int ty = std::min(std::max((yy - gy0) / kTile, 0), nty - 1);
    return !rare[std::size_t(ty) * std::size_t(ntx) + std::size_t(tx)];
  };

  // z(q) = mean over the 2 axis directions d and R, G, B of (y(q) - y(q - d)) (y(q) - y(q + d)), over
  // the box grown by the variance window.
  const Roi V = s.box.grown(kVarianceRadius, W, H);
  // Kept between frames (no fresh pages each time); referenced by name here, because a
  // thread_local named inside the parallel lambdas would be each worker's own.
  thread_local WindowSums z_kept;
  WindowSums& z = z_kept;
  z.reset(V.width(), V.height());
  // Along the axes only: at a corner where four blocks meet, a diagonal has a different
  // value on each side and would count the corner as noise; an axis never does.
  static const int dirs[2][2] = {{1, 0}, {0, 1}};
  // With a pass, the window averages relative variances, each pixel's divided by its own
  // level L = max(median^2, y^2 - own variance) + 0.01 (relMSE's weight, with y^2 - own an
  // unbiased estimate of the clean value^2, floored by the 3x3 median^2 where a firefly makes
  // it small), and the mean is scaled back to the pixel's level: a pass holds each pixel's own
  // variance, which grows with its value, so an absolute mean carried a bright pixel's
  // variance onto its dark neighbours (per-sample dof_spheres: the input's relMSE estimated
  // at 0.99 against a true 0.025), and the median alone misses thin bright structure. Without
  // a pass the estimate stays absolute (its terms are products of neighbour differences, not
  // one pixel's variance).
  auto level = [&](int x, int yy) {
    if (!use_pass) return 1.0;
    const double med2 = luminance2(&med[(std::size_t(yy - T.y0) * std::size_t(tw) + std::size_t(x - T.x0)) * 3]);
    const double own = pass_at(x, yy);
    const double y2 = ok(x, yy) ? luminance2(y.at(x, yy)) : 0.0;
    return std::max(med2, own >= 0 ? y2 - own : 0.0) + kRelMseEps;
  };
  parallel_rows(V.y0, V.y1, nthreads, [&](int yy) {
    for (int x = V.x0; x < V.x1; ++x) {
      if (const double own = use_pass ? pass_at(x, yy) : -1.0; own >= 0) {
        z.set(x - V.x0, yy - V.y0, own / level(x, yy), 1.0);
        continue;
      }
      if (!calm(x, yy)) continue;
      const float* p = y.at(x, yy);
      double sum = 0;
      int cnt = 0;
      for (const auto& d : dirs) {
        const int ax = x - d[0], ay = yy - d[1], bx = x + d[0], by = yy + d[1];
        if (!calm(ax, ay) || !calm(bx, by)) continue;
        const float* a = y.at(ax, ay);
        const float* b = y.at(bx, by);
        for (int c = 0; c < 3; ++c) {
          const double v = value(p, x, yy, c);
          sum += (v - value(a, ax, ay, c)) * (v - value(b, bx, by, c));
        }
        ++cnt;
      }
      if (cnt) z.set(x - V.x0, yy - V.y0, sum / (3.0 * cnt) / level(x, yy), 1.0);
    }
  });
  z.sum_windows(kVarianceRadius, nthreads);

  parallel_rows(s.box.y0, s.box.y1, nthreads, [&](int yy) {
    for (int x = s.box.x0; x < s.box.x1; ++x) {
      const std::size_t o = s.at(x, yy);
      if (!ok(x, yy)) continue;
      s.finite[o] = 1;
      const std::size_t i = std::size_t(yy - T.y0) * std::size_t(tw) + std::size_t(x - T.x0);
      for (int c = 0; c < 3; ++c) s.median[o * 3 + std::size_t(c)] = med[i * 3 + std::size_t(c)];
      if (demod)
        for (int c = 0; c < 3; ++c) s.albedo[o * 3 + std::size_t(c)] = albedo_at(x, yy, c);
      s.relative[o] = tile_of(x, yy);
      const std::size_t ei = std::size_t(yy - E.y0) * std::size_t(E.width()) + std::size_t(x - E.x0);
      s.excess[o] = exc[ei];
      s.variance[o] = float(std::min(std::max(z.mean(x - V.x0, yy - V.y0) * level(x, yy), 0.0), 3.0e38));
      if (use_pass) s.detail[o] = stands_out_in_own_samples(colour, *vpass, x, yy);
      s.outlier[o] = above[ei] && !s.detail[o] ? 1 : 0;
    }
  });
  return s;
}

}  // namespace mcr
