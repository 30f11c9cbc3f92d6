// BMFR's last stage: temporal anti-aliasing (Karis 2014) of the phase III result.
//
// Layout: the result (res_) and the TAA history (taa_hist_) are planar RGB, so the
// 3x3 statistics, the box and the clip run as straight loops over a row and the
// Catmull-Rom lookup reads 4 contiguous floats per tap row and channel. Per row:
//   1. column statistics of rows y-1..y+1 in the clipping space (sum, sum of squares,
//      min, max; border rows clamped, i.e. counted twice),
//   2. the clipping box per pixel (3-wide sums of step 1; SSE),
//   3. the history lookup per pixel (Catmull-Rom or bilinear; the only gather),
//   4. clip, blend, non-finite guard; written to the next history and to the output.
// Every float operation is the one of the straightforward per-pixel form (same order for
// the statistics, box and clip; the Catmull-Rom sum runs rows first: float rounding only).
#include <algorithm>
#include <cmath>
#include <limits>

#include "filters/temporal/bmfr.h"
#include "filters/temporal/bmfr_taa_avx2.h"
#include "filters/temporal/bmfr_taa_cr.h"
#include "util/parallel.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mcr {

namespace {

constexpr float kMax = std::numeric_limits<float>::max();

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

// Per-thread row scratch (grown once).
struct TaaRow {
  std::vector<float> buf;
  float* cs[3];
  float* cq[3];
  float* cmn[3];
  float* cmx[3];
  float* cur[3];
  float* lo[3];
  float* hi[3];
  float* hv[3];
  float* ok;
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

}  // namespace

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
    taa_w_ = w;
    taa_h_ = h;
    return;
  }
  const float a = float(params_.get_float("taa_alpha"));
  const bool cubic = params_.get_enum("taa_history") == "catmull_rom";
  const bool ycocg = params_.get_enum("taa_clip") == "ycocg_variance";
  const float gamma = float(params_.get_float("taa_gamma"));
  taa_next_.resize(3 * n);
  const float* R = res_.data();
  const float* G = R + n;
  const float* Bc = G + n;
  const float* H = taa_hist_.data();
  float* N = taa_next_.data();
  const int ox0 = roi.x0, ox1 = roi.x1;
  const bool avx2 = detail::taa_avx2_available();

  parallel_rows(0, h, nthreads, [&](int y) {
    thread_local TaaRow T;
    T.size(w);
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    // 1. Column statistics over rows y-1..y+1 (clamped), one pixel of padding each side.
    {
      const std::size_t r0 = std::size_t(std::max(0, y - 1)) * std::size_t(w), r1 = rb,
                        r2 = std::size_t(std::min(h - 1, y + 1)) * std::size_t(w);
      float* cs0 = T.cs[0] + 1; float* cs1 = T.cs[1] + 1; float* cs2 = T.cs[2] + 1;
      float* cq0 = T.cq[0] + 1; float* cq1 = T.cq[1] + 1; float* cq2 = T.cq[2] + 1;
      float* mn0 = T.cmn[0] + 1; float* mn1 = T.cmn[1] + 1; float* mn2 = T.cmn[2] + 1;
      float* mx0 = T.cmx[0] + 1; float* mx1 = T.cmx[1] + 1; float* mx2 = T.cmx[2] + 1;
      float* cu0 = T.cur[0]; float* cu1 = T.cur[1]; float* cu2 = T.cur[2];
      auto column = [](float v0, float v1, float v2, float& s, float& q, float& mn, float& mx) {
        s = v0 + v1 + v2;
        q = v0 * v0 + v1 * v1 + v2 * v2;
        mn = std::min(v0, std::min(v1, v2));
        mx = std::max(v0, std::max(v1, v2));
      };
      int x = 0;
      if (avx2) {
        float* const s3[3] = {cs0, cs1, cs2};
        float* const q3[3] = {cq0, cq1, cq2};
        float* const n3[3] = {mn0, mn1, mn2};
        float* const x3[3] = {mx0, mx1, mx2};
        float* const u3[3] = {cu0, cu1, cu2};
        x = detail::taa_stats_avx2(x, w, ycocg, R, G, Bc, r0, r1, r2, s3, q3, n3, x3, u3);
      }
#if defined(__SSE2__)
      {
        // std::min(v0, std::min(v1, v2)) = _mm_min_ps(_mm_min_ps(v2, v1), v0), same for max.
        auto col4 = [](__m128 v0, __m128 v1, __m128 v2, float* s, float* q, float* mn, float* mx) {
          _mm_storeu_ps(s, _mm_add_ps(_mm_add_ps(v0, v1), v2));
          _mm_storeu_ps(q, _mm_add_ps(_mm_add_ps(_mm_mul_ps(v0, v0), _mm_mul_ps(v1, v1)), _mm_mul_ps(v2, v2)));
          _mm_storeu_ps(mn, _mm_min_ps(_mm_min_ps(v2, v1), v0));
          _mm_storeu_ps(mx, _mm_max_ps(_mm_max_ps(v2, v1), v0));
        };
        const __m128 q4 = _mm_set1_ps(0.25f), h2 = _mm_set1_ps(0.5f), mq4 = _mm_set1_ps(-0.25f);
        for (; x + 4 <= w; x += 4) {
          __m128 c0[3], c1[3], c2[3];
          const std::size_t rr[3] = {r0 + std::size_t(x), r1 + std::size_t(x), r2 + std::size_t(x)};
          for (int j = 0; j < 3; ++j) {
            const __m128 r = _mm_loadu_ps(R + rr[j]), g = _mm_loadu_ps(G + rr[j]), b = _mm_loadu_ps(Bc + rr[j]);
            if (ycocg) {
              c0[j] = _mm_add_ps(_mm_add_ps(_mm_mul_ps(q4, r), _mm_mul_ps(h2, g)), _mm_mul_ps(q4, b));
              c1[j] = _mm_sub_ps(_mm_mul_ps(h2, r), _mm_mul_ps(h2, b));
              c2[j] = _mm_sub_ps(_mm_add_ps(_mm_mul_ps(mq4, r), _mm_mul_ps(h2, g)), _mm_mul_ps(q4, b));
            } else {
              c0[j] = r;
              c1[j] = g;
              c2[j] = b;
            }
          }
          col4(c0[0], c0[1], c0[2], cs0 + x, cq0 + x, mn0 + x, mx0 + x);
          col4(c1[0], c1[1], c1[2], cs1 + x, cq1 + x, mn1 + x, mx1 + x);
          col4(c2[0], c2[1], c2[2], cs2 + x, cq2 + x, mn2 + x, mx2 + x);
          _mm_storeu_ps(cu0 + x, c0[1]);
          _mm_storeu_ps(cu1 + x, c1[1]);
          _mm_storeu_ps(cu2 + x, c2[1]);
        }
      }
#endif
      if (ycocg) {
        for (; x < w; ++x) {
          float y3[3], o3[3], g3[3];
          const std::size_t rr[3] = {r0 + std::size_t(x), r1 + std::size_t(x), r2 + std::size_t(x)};
          for (int j = 0; j < 3; ++j) {
            const float r = R[rr[j]], g = G[rr[j]], b = Bc[rr[j]];
            y3[j] = 0.25f * r + 0.5f * g + 0.25f * b;
            o3[j] = 0.5f * r - 0.5f * b;
            g3[j] = -0.25f * r + 0.5f * g - 0.25f * b;
          }
          column(y3[0], y3[1], y3[2], cs0[x], cq0[x], mn0[x], mx0[x]);
          column(o3[0], o3[1], o3[2], cs1[x], cq1[x], mn1[x], mx1[x]);
          column(g3[0], g3[1], g3[2], cs2[x], cq2[x], mn2[x], mx2[x]);
          cu0[x] = y3[1];
          cu1[x] = o3[1];
          cu2[x] = g3[1];
        }
      } else {
        for (; x < w; ++x) {
          const std::size_t i0 = r0 + std::size_t(x), i1 = r1 + std::size_t(x), i2 = r2 + std::size_t(x);
          column(R[i0], R[i1], R[i2], cs0[x], cq0[x], mn0[x], mx0[x]);
          column(G[i0], G[i1], G[i2], cs1[x], cq1[x], mn1[x], mx1[x]);
          column(Bc[i0], Bc[i1], Bc[i2], cs2[x], cq2[x], mn2[x], mx2[x]);
          cu0[x] = R[i1];
          cu1[x] = G[i1];
          cu2[x] = Bc[i1];
        }
      }
      for (int k = 0; k < 3; ++k) {
        float* arr[4] = {T.cs[k], T.cq[k], T.cmn[k], T.cmx[k]};
        for (float* c : arr) {
          c[0] = c[1];
          c[w + 1] = c[w];
        }
      }
    }
    // 2. The clipping box. std::min(a, b) is (b < a ? b : a) = _mm_min_ps(b, a), and
    // std::max(a, b) is (a < b ? b : a) = _mm_max_ps(b, a): the same NaN behaviour.
    for (int k = 0; k < 3; ++k) {
      const float* cs = T.cs[k];
      const float* cq = T.cq[k];
      const float* cmn = T.cmn[k];
      const float* cmx = T.cmx[k];
      const float* cur = T.cur[k];
      float* blo = T.lo[k];
      float* bhi = T.hi[k];
      int x = avx2 ? detail::taa_box_avx2(0, w, ycocg, gamma, cs, cq, cmn, cmx, cur, blo, bhi) : 0;
#if defined(__SSE2__)
      const __m128 ninth = _mm_set1_ps(1.0f / 9.0f), g4 = _mm_set1_ps(gamma), zero = _mm_setzero_ps();
      for (; x + 4 <= w; x += 4) {
        const __m128 mn0 = _mm_loadu_ps(cmn + x), mn1 = _mm_loadu_ps(cmn + x + 1), mn2 = _mm_loadu_ps(cmn + x + 2);
        const __m128 mx0 = _mm_loadu_ps(cmx + x), mx1 = _mm_loadu_ps(cmx + x + 1), mx2 = _mm_loadu_ps(cmx + x + 2);
        __m128 lo = _mm_min_ps(_mm_min_ps(mn2, mn1), mn0);  // std::min(mn0, std::min(mn1, mn2))
        __m128 hi = _mm_max_ps(_mm_max_ps(mx2, mx1), mx0);
        if (ycocg) {
          const __m128 mean =
              _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_loadu_ps(cs + x), _mm_loadu_ps(cs + x + 1)), _mm_loadu_ps(cs + x + 2)), ninth);
          const __m128 m2 =
              _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_loadu_ps(cq + x), _mm_loadu_ps(cq + x + 1)), _mm_loadu_ps(cq + x + 2)), ninth);
          const __m128 var = _mm_max_ps(_mm_sub_ps(m2, _mm_mul_ps(mean, mean)), zero);  // std::max(0, t)
          const __m128 sd = _mm_mul_ps(g4, _mm_sqrt_ps(var));
          const __m128 c = _mm_loadu_ps(cur + x);
          lo = _mm_max_ps(_mm_min_ps(c, _mm_sub_ps(mean, sd)), lo);  // std::max(lo, std::min(mean - sd, cur))
          hi = _mm_min_ps(_mm_max_ps(c, _mm_add_ps(mean, sd)), hi);  // std::min(hi, std::max(mean + sd, cur))
        }
        _mm_storeu_ps(blo + x, lo);
        _mm_storeu_ps(bhi + x, hi);
      }
#endif
      for (; x < w; ++x) {
        float lo = std::min(cmn[x], std::min(cmn[x + 1], cmn[x + 2]));
        float hi = std::max(cmx[x], std::max(cmx[x + 1], cmx[x + 2]));
        if (ycocg) {
          const float mean = (cs[x] + cs[x + 1] + cs[x + 2]) * (1.0f / 9.0f);
          const float var = std::max(0.0f, (cq[x] + cq[x + 1] + cq[x + 2]) * (1.0f / 9.0f) - mean * mean);
          const float sd = gamma * std::sqrt(var);
          lo = std::max(lo, std::min(mean - sd, cur[x]));
          hi = std::min(hi, std::max(mean + sd, cur[x]));
        }
        blo[x] = lo;
        bhi[x] = hi;
      }
    }
    // 3. History lookup.
    {
      float* h0 = T.hv[0];
      float* h1 = T.hv[1];
      float* h2 = T.hv[2];
      float* okr = T.ok;
      if (cubic && avx2) {
        detail::taa_lookup_cr_avx2(w, h, n, H, rep.prev_x.data() + rb, rep.prev_y.data() + rb, rep.inside.data() + rb, h0,
                                   h1, h2, okr);
      } else {
        for (int x = 0; x < w; ++x) {
          const std::size_t i = rb + std::size_t(x);
          float hv[3] = {0, 0, 0};
          bool ok;
          if (cubic)
            ok = rep.inside[i] && catmull_rom_planar(H, w, h, n, rep.prev_x[i], rep.prev_y[i], hv);
          else
            ok = bilinear_planar(rep, H, n, i, hv);
          h0[x] = hv[0];
          h1[x] = hv[1];
          h2[x] = hv[2];
          okr[x] = ok ? 1.0f : 0.0f;
        }
      }
    }
    // 4. Clip, blend, guard (branch-free: vectorised).
    {
      const float* h0 = T.hv[0];
      const float* h1 = T.hv[1];
      const float* h2 = T.hv[2];
      const float* h2_ = h2;
      const float* okr = T.ok;
      const float *lo0 = T.lo[0], *lo1 = T.lo[1], *lo2 = T.lo[2];
      const float *hi0 = T.hi[0], *hi1 = T.hi[1], *hi2 = T.hi[2];
      const float* cr = R + rb;
      const float* cg = G + rb;
      const float* cb = Bc + rb;
      float* nr = N + rb;
      float* ng = nr + n;
      float* nb = ng + n;
      int x = 0;
      if (avx2) {
        const float* const hv3[3] = {h0, h1, h2};
        const float* const lo3[3] = {lo0, lo1, lo2};
        const float* const hi3[3] = {hi0, hi1, hi2};
        x = detail::taa_clip_avx2(x, w, ycocg, a, hv3, okr, lo3, hi3, cr, cg, cb, nr, ng, nb);
      }
#if defined(__SSE2__)
      {
        const __m128 q4 = _mm_set1_ps(0.25f), h2 = _mm_set1_ps(0.5f), mq4 = _mm_set1_ps(-0.25f);
        const __m128 one = _mm_set1_ps(1.0f), big = _mm_set1_ps(kMax), sign = _mm_set1_ps(-0.0f), zero = _mm_setzero_ps();
        const __m128 t5 = _mm_set1_ps(1e-5f), t30 = _mm_set1_ps(1e-30f), av = _mm_set1_ps(a);
        auto sel = [](__m128 m, __m128 t, __m128 f) { return _mm_or_ps(_mm_and_ps(m, t), _mm_andnot_ps(m, f)); };
        auto fabs4 = [&](__m128 v) { return _mm_andnot_ps(sign, v); };
        // std::clamp(v, lo, hi) = v < lo ? lo : (hi < v ? hi : v)
        auto clamp4 = [&](__m128 v, __m128 lo, __m128 hi) {
          return sel(_mm_cmplt_ps(v, lo), lo, sel(_mm_cmplt_ps(hi, v), hi, v));
        };
        for (; x + 4 <= w; x += 4) {
          const __m128 v0 = _mm_loadu_ps(h0 + x), v1 = _mm_loadu_ps(h1 + x), v2 = _mm_loadu_ps(h2_ + x);
          const __m128 l0 = _mm_loadu_ps(lo0 + x), l1 = _mm_loadu_ps(lo1 + x), l2 = _mm_loadu_ps(lo2 + x);
          const __m128 u0 = _mm_loadu_ps(hi0 + x), u1 = _mm_loadu_ps(hi1 + x), u2 = _mm_loadu_ps(hi2 + x);
          __m128 s0, s1, s2;
          if (ycocg) {
            s0 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(q4, v0), _mm_mul_ps(h2, v1)), _mm_mul_ps(q4, v2));
            s1 = _mm_sub_ps(_mm_mul_ps(h2, v0), _mm_mul_ps(h2, v2));
            s2 = _mm_sub_ps(_mm_add_ps(_mm_mul_ps(mq4, v0), _mm_mul_ps(h2, v1)), _mm_mul_ps(q4, v2));
            const __m128 c0 = _mm_mul_ps(h2, _mm_add_ps(l0, u0)), c1 = _mm_mul_ps(h2, _mm_add_ps(l1, u1)),
                         c2 = _mm_mul_ps(h2, _mm_add_ps(l2, u2));
            const __m128 d0 = _mm_sub_ps(s0, c0), d1 = _mm_sub_ps(s1, c1), d2 = _mm_sub_ps(s2, c2);
            const __m128 e0 = _mm_mul_ps(h2, _mm_sub_ps(u0, l0)), e1 = _mm_mul_ps(h2, _mm_sub_ps(u1, l1)),
                         e2 = _mm_mul_ps(h2, _mm_sub_ps(u2, l2));
            const __m128 tol = _mm_add_ps(_mm_mul_ps(t5, _mm_add_ps(fabs4(c0), e0)), t30);
            const __m128 a0 = fabs4(d0), a1 = fabs4(d1), a2 = fabs4(d2);
            __m128 ratio = one;
            // std::max(ratio, q) = _mm_max_ps(q, ratio)
            ratio = sel(_mm_and_ps(_mm_cmpgt_ps(e0, tol), _mm_cmpgt_ps(a0, e0)), _mm_max_ps(_mm_div_ps(a0, e0), ratio), ratio);
            ratio = sel(_mm_and_ps(_mm_cmpgt_ps(e1, tol), _mm_cmpgt_ps(a1, e1)), _mm_max_ps(_mm_div_ps(a1, e1), ratio), ratio);
            ratio = sel(_mm_and_ps(_mm_cmpgt_ps(e2, tol), _mm_cmpgt_ps(a2, e2)), _mm_max_ps(_mm_div_ps(a2, e2), ratio), ratio);
            const __m128 scale = _mm_and_ps(_mm_cmpgt_ps(ratio, one), _mm_cmple_ps(ratio, big));
            s0 = sel(scale, _mm_add_ps(c0, _mm_div_ps(d0, ratio)), s0);
            s1 = sel(scale, _mm_add_ps(c1, _mm_div_ps(d1, ratio)), s1);
            s2 = sel(scale, _mm_add_ps(c2, _mm_div_ps(d2, ratio)), s2);
          } else {
            s0 = v0;
            s1 = v1;
            s2 = v2;
          }
          s0 = clamp4(s0, l0, u0);
          s1 = clamp4(s1, l1, u1);
          s2 = clamp4(s2, l2, u2);
          __m128 k0, k1, k2;
          if (ycocg) {
            const __m128 t = _mm_sub_ps(s0, s2);
            k0 = _mm_add_ps(t, s1);
            k1 = _mm_add_ps(s0, s2);
            k2 = _mm_sub_ps(t, s1);
          } else {
            k0 = s0;
            k1 = s1;
            k2 = s2;
          }
          const __m128 ok = _mm_cmpneq_ps(_mm_loadu_ps(okr + x), zero);
          const __m128 q0 = _mm_loadu_ps(cr + x), q1 = _mm_loadu_ps(cg + x), q2 = _mm_loadu_ps(cb + x);
          const __m128 o0 = _mm_add_ps(k0, _mm_mul_ps(av, _mm_sub_ps(q0, k0)));
          const __m128 o1 = _mm_add_ps(k1, _mm_mul_ps(av, _mm_sub_ps(q1, k1)));
          const __m128 o2 = _mm_add_ps(k2, _mm_mul_ps(av, _mm_sub_ps(q2, k2)));
          _mm_storeu_ps(nr + x, sel(_mm_and_ps(ok, _mm_cmple_ps(fabs4(o0), big)), o0, q0));
          _mm_storeu_ps(ng + x, sel(_mm_and_ps(ok, _mm_cmple_ps(fabs4(o1), big)), o1, q1));
          _mm_storeu_ps(nb + x, sel(_mm_and_ps(ok, _mm_cmple_ps(fabs4(o2), big)), o2, q2));
        }
      }
#endif
      for (; x < w; ++x) {
        float hs0, hs1, hs2;
        if (ycocg) {
          hs0 = 0.25f * h0[x] + 0.5f * h1[x] + 0.25f * h2[x];
          hs1 = 0.5f * h0[x] - 0.5f * h2[x];
          hs2 = -0.25f * h0[x] + 0.5f * h1[x] - 0.25f * h2[x];
          // Clip towards the box centre along the line to the history (Karis 2014):
          // keeps the history's hue instead of moving each channel on its own. A channel
          // whose box is flat (within float rounding of the luma) does not steer the
          // clip: the final clamp handles it.
          const float c0 = 0.5f * (lo0[x] + hi0[x]), c1 = 0.5f * (lo1[x] + hi1[x]), c2 = 0.5f * (lo2[x] + hi2[x]);
          const float d0 = hs0 - c0, d1 = hs1 - c1, d2 = hs2 - c2;
          const float e0 = 0.5f * (hi0[x] - lo0[x]), e1 = 0.5f * (hi1[x] - lo1[x]), e2 = 0.5f * (hi2[x] - lo2[x]);
          const float tol = 1e-5f * (std::fabs(c0) + e0) + 1e-30f;
          float ratio = 1.0f;
          const float a0 = std::fabs(d0), a1 = std::fabs(d1), a2 = std::fabs(d2);
          const float q0 = a0 / e0, q1 = a1 / e1, q2 = a2 / e2;
          ratio = (e0 > tol && a0 > e0) ? std::max(ratio, q0) : ratio;
          ratio = (e1 > tol && a1 > e1) ? std::max(ratio, q1) : ratio;
          ratio = (e2 > tol && a2 > e2) ? std::max(ratio, q2) : ratio;
          const bool scale = ratio > 1.0f && ratio <= kMax;
          const float t0 = c0 + d0 / ratio, t1 = c1 + d1 / ratio, t2 = c2 + d2 / ratio;
          hs0 = scale ? t0 : hs0;
          hs1 = scale ? t1 : hs1;
          hs2 = scale ? t2 : hs2;
        } else {
          hs0 = h0[x];
          hs1 = h1[x];
          hs2 = h2[x];
        }
        hs0 = std::clamp(hs0, lo0[x], hi0[x]);
        hs1 = std::clamp(hs1, lo1[x], hi1[x]);
        hs2 = std::clamp(hs2, lo2[x], hi2[x]);
        float hc0, hc1, hc2;
        if (ycocg) {
          const float t = hs0 - hs2;
          hc0 = t + hs1;
          hc1 = hs0 + hs2;
          hc2 = t - hs1;
        } else {
          hc0 = hs0;
          hc1 = hs1;
          hc2 = hs2;
        }
        const float v0 = hc0 + a * (cr[x] - hc0), v1 = hc1 + a * (cg[x] - hc1), v2 = hc2 + a * (cb[x] - hc2);
        const bool ok = okr[x] != 0.0f;
        nr[x] = ok && std::fabs(v0) <= kMax ? v0 : cr[x];
        ng[x] = ok && std::fabs(v1) <= kMax ? v1 : cg[x];
        nb[x] = ok && std::fabs(v2) <= kMax ? v2 : cb[x];
      }
      if (y >= roi.y0 && y < roi.y1) {
        float* o = out.data() + rb * 3;
        for (int x = ox0; x < ox1; ++x) {
          o[std::size_t(x) * 3] = nr[x];
          o[std::size_t(x) * 3 + 1] = ng[x];
          o[std::size_t(x) * 3 + 2] = nb[x];
        }
      }
    }
  });
  std::swap(taa_hist_, taa_next_);
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
