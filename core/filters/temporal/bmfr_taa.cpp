// BMFR's last stage: temporal anti-aliasing (Karis 2014) of the phase III result.
//
// Layout: the result and the TAA history are planar RGB, so the 3x3 statistics, the box
// and the clip run as straight loops over a row and the Catmull-Rom lookup reads 4
// contiguous floats per tap row and channel. Per row:
//   1. column statistics of rows y-1..y+1 in the clipping space (sum, sum of squares,
//      min, max; border rows clamped, i.e. counted twice),
//   2. the clipping box per pixel (3-wide sums of step 1),
//   3. the history lookup per pixel (Catmull-Rom or bilinear; the only gather),
//   4. clip, blend, non-finite guard; written to the next history and to the output.
// One source for every vector width: the row is taa_row<W>, W float lanes of GCC vector
// extensions (kernels/simd_lanes.h), built at the generic level with W = 4 and for AVX2
// with W = 8 (util/isa.h); a row's last w % W pixels run the same code on a partly
// filled vector. Every lane does
// the float operations of the straightforward per-pixel form in its order (no FMA: the
// core has -ffp-contract=off; min, max and clamp keep the operand order of the std::
// forms, which decides what a NaN gives), so both builds give the same bits. Only the
// Catmull-Rom sum departs from the per-pixel form (rows first: float rounding only).
//
// W-lane vectors pass between always-inlined helpers only: no ABI boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "filters/temporal/bmfr_taa.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "filters/temporal/bmfr.h"
#include "kernels/simd_lanes.h"
#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

namespace {

using simd::for_lanes;
using simd::load;
using simd::store;
using simd::vabs;
using simd::vclamp;
using simd::vmax;
using simd::vmin;
using simd::vsqrt;

constexpr float kMax = std::numeric_limits<float>::max();

// Shorthands, and the two helpers of the Catmull-Rom lookup that depend on the width.
template <int W>
using VF = typename simd::Vec<W>::f;
template <int W>
using VI = typename simd::Vec<W>::i;  // lane masks (-1 / 0) of comparisons
using F4 = VF<4>;

// The W / 4 groups of 4 lanes side by side, q[0] in the low lanes.
template <int W>
MCR_INLINE VF<W> join(const F4* q) {
  if constexpr (W == 4) {
    return q[0];
  } else {
    static_assert(W == 8, "4 or 8 lanes");
    return __builtin_shufflevector(q[0], q[1], 0, 1, 2, 3, 4, 5, 6, 7);
  }
}

// Lane 4p: (v[4p] + v[4p+1]) + (v[4p+2] + v[4p+3]), the sum of each group of 4.
template <int W>
MCR_INLINE VF<W> group_sums(VF<W> v) {
  if constexpr (W == 4) {
    const VF<W> s = v + __builtin_shufflevector(v, v, 1, 0, 3, 2);
    return s + __builtin_shufflevector(s, s, 2, 3, 0, 1);
  } else {
    static_assert(W == 8, "4 or 8 lanes");
    const VF<W> s = v + __builtin_shufflevector(v, v, 1, 0, 3, 2, 5, 4, 7, 6);
    return s + __builtin_shufflevector(s, s, 2, 3, 0, 1, 6, 7, 4, 5);
  }
}

// ---- the history lookups (scalar but for the interior Catmull-Rom taps) ----

inline void cr_weights(float t, float* wt) {
  const float t2 = t * t, t3 = t2 * t;
  wt[0] = 0.5f * (-t3 + 2 * t2 - t);
  wt[1] = 0.5f * (3 * t3 - 5 * t2 + 2);
  wt[2] = 0.5f * (-3 * t3 + 4 * t2 + t);
  wt[3] = 0.5f * (t3 - t2);
}

// The Catmull-Rom taps of one pixel's history sample (pixel centres at integers): none
// when the sample lies outside the frame; interior when no tap needs clamping.
struct CrTap {
  int x;
  bool ok, interior;
  int bx, by;  // first tap
  float wx[4], wy[4];
};

inline void cr_prepare(int w, int h, int x, float px, float py, bool inside, CrTap& t) {
  t.x = x;
  t.ok = t.interior = false;
  if (!inside || !(px >= -0.5f && py >= -0.5f && px <= float(w) - 0.5f && py <= float(h) - 0.5f)) return;
  t.ok = true;
  const int ix = floor_int(px), iy = floor_int(py);
  cr_weights(px - float(ix), t.wx);
  cr_weights(py - float(iy), t.wy);
  t.bx = ix - 1;
  t.by = iy - 1;
  t.interior = t.bx >= 0 && t.by >= 0 && t.bx + 3 < w && t.by + 3 < h;
}

// A sample near the border: taps clamped to it.
inline void cr_clamped(const float* H, int w, int h, std::size_t n, const CrTap& t, float* out) {
  int xs[4], ys[4];
  for (int i = 0; i < 4; ++i) {
    xs[i] = std::clamp(t.bx + i, 0, w - 1);
    ys[i] = std::clamp(t.by + i, 0, h - 1);
  }
  for (int c = 0; c < 3; ++c) {
    const float* p = H + std::size_t(c) * n;
    float acc = 0;
    for (int j = 0; j < 4; ++j) {
      const float* row = p + std::size_t(ys[j]) * std::size_t(w);
      float r = 0;
      for (int i = 0; i < 4; ++i) r += t.wx[i] * row[xs[i]];
      acc += t.wy[j] * r;
    }
    out[c] = acc;
  }
}

// m <= W / 4 interior samples, 4 lanes each (lanes = tap columns): per channel the 4 tap
// rows weighted by wy, times wx, summed per group. Groups past m repeat g[0], unstored.
template <int W>
MCR_INLINE void cr_interior(const float* H, int w, std::size_t n, const CrTap* g, int m, float* const hv[3],
                            float* okr) {
  constexpr int P = W / 4;
  const CrTap* t[P];
  const float* base[P];
  for (int p = 0; p < P; ++p) {
    t[p] = &g[p < m ? p : 0];
    base[p] = H + std::size_t(t[p]->by) * std::size_t(w) + std::size_t(t[p]->bx);
  }
  F4 q[P];
  VF<W> wy[4];
  for (int j = 0; j < 4; ++j) {
    for (int p = 0; p < P; ++p) q[p] = simd::splat<4>(t[p]->wy[j]);
    wy[j] = join<W>(q);
  }
  for (int p = 0; p < P; ++p) q[p] = load<4>(t[p]->wx, 4);
  const VF<W> wx = join<W>(q);
  for (int c = 0; c < 3; ++c) {
    const std::size_t plane = std::size_t(c) * n;
    auto taps = [&](int j) __attribute__((always_inline)) {  // tap row j of every sample
      const std::size_t o = plane + std::size_t(j) * std::size_t(w);
      for (int p = 0; p < P; ++p) q[p] = load<4>(base[p] + o, 4);
      return join<W>(q);
    };
    VF<W> s = wy[0] * taps(0);
    for (int j = 1; j < 4; ++j) s = s + wy[j] * taps(j);
    const VF<W> sum = group_sums<W>(s * wx);
    for (int p = 0; p < m; ++p) hv[c][t[p]->x] = sum[4 * p];
  }
  for (int p = 0; p < m; ++p) okr[t[p]->x] = 1.0f;
}

// Bilinear sample of the planar history over the taps inside the frame, normalised by
// their weights (Reprojection::sample on a planar image).
inline bool bilinear_planar(const Reprojection& rep, const float* hist, std::size_t n, std::size_t i, float* out) {
  const std::uint8_t mask = rep.inside[i];
  if (!mask) return false;
  const float px = rep.prev_x[i], py = rep.prev_y[i];
  const int x0 = floor_int(px), y0 = floor_int(py);
  const float fx = px - float(x0), fy = py - float(y0);
  const float wt[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  float sum = 0, acc[3] = {0, 0, 0};
  for (int k = 0; k < 4; ++k) {
    if (!(mask & (1u << k)) || wt[k] <= 0.0f) continue;
    const std::size_t t = std::size_t(y0 + (k >> 1)) * std::size_t(rep.width) + std::size_t(x0 + (k & 1));
    sum += wt[k];
    for (int c = 0; c < 3; ++c) acc[c] += wt[k] * hist[std::size_t(c) * n + t];
  }
  if (sum <= 1e-6f) return false;
  for (int c = 0; c < 3; ++c) out[c] = acc[c] / sum;
  return true;
}

// ---- one row ----

// Per-thread row scratch (grown once).
struct TaaRow {
  std::vector<float> buf;
  float* cs[3];   // column sums, one pixel of padding each side
  float* cq[3];   // column sums of squares
  float* cmn[3];  // column min
  float* cmx[3];  // column max
  float* cur[3];  // the centre row in the clipping space
  float* lo[3];   // the clipping box
  float* hi[3];
  float* hv[3];  // the history sample
  float* ok;     // 1: the pixel has one
  void size(int w) {
    const std::size_t stride = (std::size_t(w) + 16) & ~std::size_t(7);
    if (buf.size() < stride * 25) buf.assign(stride * 25, 0.0f);
    float* p = buf.data();
    auto take = [&]() {
      float* r = p;
      p += stride;
      return r;
    };
    for (int k = 0; k < 3; ++k) {
      cs[k] = take();
      cq[k] = take();
      cmn[k] = take();
      cmx[k] = take();
      cur[k] = take();
      lo[k] = take();
      hi[k] = take();
      hv[k] = take();
    }
    ok = take();
  }
};

struct TaaJob {
  TaaSettings s;
  const Reprojection* rep;
  int w, h;
  std::size_t n;
  const float* cur[3];  // the current frame's planes
  const float* H;       // the history
  float* next;
  Image* out;
  Roi roi;
};

// RGB -> YCoCg (Karis 2014): Y = r/4 + g/2 + b/4, Co = (r - b)/2, Cg = -r/4 + g/2 - b/4.
template <class V>
MCR_INLINE void to_ycocg(V r, V g, V b, V& y, V& co, V& cg) {
  y = 0.25f * r + 0.5f * g + 0.25f * b;
  co = 0.5f * r - 0.5f * b;
  cg = -0.25f * r + 0.5f * g - 0.25f * b;
}

template <int W>
MCR_INLINE void taa_row(const TaaJob& J, TaaRow& T, int y) {
  using V = VF<W>;
  const int w = J.w, h = J.h;
  const bool ycocg = J.s.ycocg;
  const std::size_t rb = std::size_t(y) * std::size_t(w);
  // 1. Column statistics over rows y-1..y+1 (clamped), one pixel of padding each side.
  // (The lambdas are always_inline: one compiled on its own would not get the AVX2
  // target of taa_row_avx2.)
  {
    const std::size_t rows[3] = {std::size_t(std::max(0, y - 1)) * std::size_t(w), rb,
                                 std::size_t(std::min(h - 1, y + 1)) * std::size_t(w)};
    for_lanes<W>(w, [&](int x, int n) __attribute__((always_inline)) {
      V v[3][3];  // channel, row
      for (int j = 0; j < 3; ++j) {
        const V r = load<W>(J.cur[0] + rows[j] + x, n), g = load<W>(J.cur[1] + rows[j] + x, n),
                b = load<W>(J.cur[2] + rows[j] + x, n);
        if (ycocg) {
          to_ycocg(r, g, b, v[0][j], v[1][j], v[2][j]);
        } else {
          v[0][j] = r;
          v[1][j] = g;
          v[2][j] = b;
        }
      }
      for (int k = 0; k < 3; ++k) {
        const V v0 = v[k][0], v1 = v[k][1], v2 = v[k][2];
        const int i = x + 1;
        store<W>(T.cs[k] + i, v0 + v1 + v2, n);
        store<W>(T.cq[k] + i, v0 * v0 + v1 * v1 + v2 * v2, n);
        store<W>(T.cmn[k] + i, vmin(vmin(v2, v1), v0), n);  // std::min(v0, std::min(v1, v2))
        store<W>(T.cmx[k] + i, vmax(vmax(v2, v1), v0), n);
        store<W>(T.cur[k] + x, v1, n);
      }
    });
    for (int k = 0; k < 3; ++k)
      for (float* c : {T.cs[k], T.cq[k], T.cmn[k], T.cmx[k]}) {
        c[0] = c[1];
        c[w + 1] = c[w];
      }
  }
  // 2. The clipping box: the 3x3 min/max, for ycocg intersected with mean +- gamma sd
  // (each widened to hold the current pixel).
  for (int k = 0; k < 3; ++k) {
    const float *cs = T.cs[k], *cq = T.cq[k], *cmn = T.cmn[k], *cmx = T.cmx[k], *cur = T.cur[k];
    for_lanes<W>(w, [&](int x, int n) __attribute__((always_inline)) {
      auto sum3 = [&](const float* c) __attribute__((always_inline)) {
        return load<W>(c + x, n) + load<W>(c + x + 1, n) + load<W>(c + x + 2, n);
      };
      V lo = vmin(vmin(load<W>(cmn + x + 2, n), load<W>(cmn + x + 1, n)), load<W>(cmn + x, n));
      V hi = vmax(vmax(load<W>(cmx + x + 2, n), load<W>(cmx + x + 1, n)), load<W>(cmx + x, n));
      if (ycocg) {
        const V mean = sum3(cs) * (1.0f / 9.0f);
        const V var = vmax(sum3(cq) * (1.0f / 9.0f) - mean * mean, simd::splat<W>(0.0f));  // std::max(0, t)
        const V sd = J.s.gamma * vsqrt<W>(var);
        const V c = load<W>(cur + x, n);
        lo = vmax(vmin(c, mean - sd), lo);  // std::max(lo, std::min(mean - sd, cur))
        hi = vmin(vmax(c, mean + sd), hi);  // std::min(hi, std::max(mean + sd, cur))
      }
      store<W>(T.lo[k] + x, lo, n);
      store<W>(T.hi[k] + x, hi, n);
    });
  }
  // 3. History lookup.
  {
    const Reprojection& rep = *J.rep;
    if (J.s.catmull_rom) {
      // Interior samples W / 4 at a time, in the order met.
      constexpr int P = W / 4;
      CrTap g[P];
      int m = 0;
      for (int x = 0; x < w; ++x) {
        const std::size_t i = rb + std::size_t(x);
        CrTap& t = g[m];
        cr_prepare(w, h, x, rep.prev_x[i], rep.prev_y[i], rep.inside[i] != 0, t);
        if (t.interior) {
          if (++m == P) {
            cr_interior<W>(J.H, w, J.n, g, P, T.hv, T.ok);
            m = 0;
          }
          continue;
        }
        float hv[3] = {0, 0, 0};
        if (t.ok) cr_clamped(J.H, w, h, J.n, t, hv);
        for (int c = 0; c < 3; ++c) T.hv[c][x] = hv[c];
        T.ok[x] = t.ok ? 1.0f : 0.0f;
      }
      if (m) cr_interior<W>(J.H, w, J.n, g, m, T.hv, T.ok);
    } else {
      for (int x = 0; x < w; ++x) {
        float hv[3] = {0, 0, 0};
        const bool ok = bilinear_planar(rep, J.H, J.n, rb + std::size_t(x), hv);
        for (int c = 0; c < 3; ++c) T.hv[c][x] = hv[c];
        T.ok[x] = ok ? 1.0f : 0.0f;
      }
    }
  }
  // 4. Clip, blend, guard.
  float* nx[3] = {J.next + rb, J.next + J.n + rb, J.next + 2 * J.n + rb};
  const V one = simd::splat<W>(1.0f), big = simd::splat<W>(kMax), zero = simd::splat<W>(0.0f);
  for_lanes<W>(w, [&](int x, int n) __attribute__((always_inline)) {
    V s[3], l[3], u[3];
    for (int k = 0; k < 3; ++k) {
      s[k] = load<W>(T.hv[k] + x, n);
      l[k] = load<W>(T.lo[k] + x, n);
      u[k] = load<W>(T.hi[k] + x, n);
    }
    if (ycocg) {
      const V r = s[0], g = s[1], b = s[2];
      to_ycocg(r, g, b, s[0], s[1], s[2]);
      // Clip towards the box centre along the line to the history (Karis 2014): keeps
      // the history's hue instead of moving each channel on its own. A channel whose
      // box is flat (within float rounding of the luma) does not steer the clip: the
      // final clamp handles it.
      V c[3], d[3], e[3], a[3];
      for (int k = 0; k < 3; ++k) {
        c[k] = 0.5f * (l[k] + u[k]);
        d[k] = s[k] - c[k];
        e[k] = 0.5f * (u[k] - l[k]);
        a[k] = vabs<W>(d[k]);
      }
      const V tol = 1e-5f * (vabs<W>(c[0]) + e[0]) + 1e-30f;
      V ratio = one;
      for (int k = 0; k < 3; ++k)  // std::max(ratio, q) = vmax(q, ratio)
        ratio = ((e[k] > tol) & (a[k] > e[k])) ? vmax(a[k] / e[k], ratio) : ratio;
      const VI<W> scale = (ratio > one) & (ratio <= big);
      for (int k = 0; k < 3; ++k) s[k] = scale ? c[k] + d[k] / ratio : s[k];
    }
    for (int k = 0; k < 3; ++k) s[k] = vclamp(s[k], l[k], u[k]);
    if (ycocg) {  // back to RGB: r = Y + Co - Cg, g = Y + Cg, b = Y - Co - Cg
      const V t = s[0] - s[2];
      const V r = t + s[1], g = s[0] + s[2], b = t - s[1];
      s[0] = r;
      s[1] = g;
      s[2] = b;
    }
    const VI<W> ok = load<W>(T.ok + x, n) != zero;
    const V alpha = J.s.alpha_floor ? vmax(load<W>(J.s.alpha_floor + rb + x, n), simd::splat<W>(J.s.alpha))
                                    : simd::splat<W>(J.s.alpha);  // std::max(alpha, floor)
    for (int k = 0; k < 3; ++k) {
      const V q = load<W>(J.cur[k] + rb + x, n);
      const V o = s[k] + alpha * (q - s[k]);
      store<W>(nx[k] + x, (ok & (vabs<W>(o) <= big)) ? o : q, n);
    }
  });
  if (J.out && y >= J.roi.y0 && y < J.roi.y1) {
    float* o = J.out->data() + rb * 3;
    for (int x = J.roi.x0; x < J.roi.x1; ++x)
      for (int c = 0; c < 3; ++c) o[std::size_t(x) * 3 + std::size_t(c)] = nx[c][x];
  }
}

void taa_row_generic(const TaaJob& J, TaaRow& T, int y) { taa_row<4>(J, T, y); }
MCR_TARGET_AVX2 void taa_row_avx2(const TaaJob& J, TaaRow& T, int y) { taa_row<8>(J, T, y); }

}  // namespace

void temporal_antialias(const TaaSettings& s, const Reprojection& rep, const float* current, const float* history,
                        float* next, int nthreads, Image* out, const Roi& roi) {
  const int w = rep.width, h = rep.height;
  const std::size_t n = std::size_t(w) * std::size_t(h);
  const TaaJob J{s, &rep, w, h, n, {current, current + n, current + 2 * n}, history, next, out, roi.clipped(w, h)};
  const bool avx2 = isa_at_least(Isa::Avx2);
  parallel_rows(0, h, nthreads, [&](int y) {
    thread_local TaaRow T;
    T.size(w);
    if (avx2)
      taa_row_avx2(J, T, y);
    else
      taa_row_generic(J, T, y);
  });
}

// TAA (Karis 2014): the previous output reprojected by the motion pass (bilinear or
// Catmull-Rom), clipped to the current result's 3x3 neighbourhood, blended with weight
// taa_alpha for the current frame. taa_clip=ycocg_variance: the box is the intersection
// of the 3x3 min/max and mean +- taa_gamma standard deviations (Salvi 2016), in YCoCg
// (Karis 2014): tighter than the plain min/max, which lets outliers of the fit through.
// taa_clip=rgb_minmax: the 3x3 min/max in RGB.
// Reads res_ (planar RGB), writes the new history and the roi of `out` (interleaved RGB).
void BmfrFilter::taa(const Reprojection& rep, bool hist, const Roi& roi, Image& out, int nthreads) {
  const int w = rep.width, h = rep.height;
  const std::size_t n = std::size_t(w) * std::size_t(h);
  if (!hist) {
    // No usable history: the result is the output and the new history.
    write_planar_roi(res_.data(), n, w, roi, out, nthreads);
    std::swap(taa_hist_, res_);
  } else {
    TaaSettings s;
    s.alpha = float(params_.get_float("taa_alpha"));
    s.catmull_rom = params_.get_enum("taa_history") == "catmull_rom";
    s.ycocg = params_.get_enum("taa_clip") == "ycocg_variance";
    s.gamma = float(params_.get_float("taa_gamma"));
    if (classes_.mirror) {  // mirrors: the blend weight at least mirror_taa_alpha
      class_values(classes_, SurfaceClasses::kMirror, float(params_.get_float("mirror_taa_alpha")), taa_alpha_);
      s.alpha_floor = taa_alpha_.data();
    }
    taa_next_.resize(3 * n);
    temporal_antialias(s, rep, res_.data(), taa_hist_.data(), taa_next_.data(), nthreads, &out, roi);
    std::swap(taa_hist_, taa_next_);
  }
  taa_w_ = w;
  taa_h_ = h;
}

void BmfrFilter::write_planar_roi(const float* planar, std::size_t n, int w, const Roi& roi, Image& out, int nthreads) {
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    const float* r = planar + rb;
    const float* g = r + n;
    const float* b = g + n;
    float* o = out.data() + rb * 3;
    for (int x = roi.x0; x < roi.x1; ++x) {
      o[std::size_t(x) * 3] = r[x];
      o[std::size_t(x) * 3 + 1] = g[x];
      o[std::size_t(x) * 3 + 2] = b[x];
    }
  });
}

}  // namespace mcr
