#include "filters/temporal/bmfr_taa_avx2.h"

#include <limits>

#include "filters/temporal/bmfr_taa_cr.h"
#include "util/isa.h"

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#include <immintrin.h>

namespace mcr::detail {

namespace {

constexpr float kMax = std::numeric_limits<float>::max();

#define MCR_AVX2 __attribute__((target("avx2"), always_inline)) inline
// The SSE2 comparisons: lt, gt, le ordered; neq unordered.
MCR_AVX2 __m256 cmplt8(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_LT_OS); }
MCR_AVX2 __m256 cmpgt8(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_GT_OS); }
MCR_AVX2 __m256 cmple8(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_LE_OS); }
MCR_AVX2 __m256 cmpneq8(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_NEQ_UQ); }
MCR_AVX2 __m256 sel8(__m256 m, __m256 t, __m256 f) { return _mm256_or_ps(_mm256_and_ps(m, t), _mm256_andnot_ps(m, f)); }
MCR_AVX2 __m256 fabs8(__m256 v) { return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), v); }
// std::clamp(v, lo, hi) = v < lo ? lo : (hi < v ? hi : v)
MCR_AVX2 __m256 clamp8(__m256 v, __m256 lo, __m256 hi) { return sel8(cmplt8(v, lo), lo, sel8(cmplt8(hi, v), hi, v)); }
// std::min(v0, std::min(v1, v2)) = _mm256_min_ps(_mm256_min_ps(v2, v1), v0), same for max.
MCR_AVX2 void col8(__m256 v0, __m256 v1, __m256 v2, float* s, float* q, float* mn, float* mx) {
  _mm256_storeu_ps(s, _mm256_add_ps(_mm256_add_ps(v0, v1), v2));
  _mm256_storeu_ps(q,
                   _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(v0, v0), _mm256_mul_ps(v1, v1)), _mm256_mul_ps(v2, v2)));
  _mm256_storeu_ps(mn, _mm256_min_ps(_mm256_min_ps(v2, v1), v0));
  _mm256_storeu_ps(mx, _mm256_max_ps(_mm256_max_ps(v2, v1), v0));
}
#undef MCR_AVX2

}  // namespace

bool taa_avx2_available() { return isa_at_least(Isa::Avx2); }

__attribute__((target("avx2"))) int taa_stats_avx2(int x, int w, bool ycocg, const float* R, const float* G,
                                                   const float* Bc, std::size_t r0, std::size_t r1, std::size_t r2,
                                                   float* const cs[3], float* const cq[3], float* const mn[3],
                                                   float* const mx[3], float* const cu[3]) {
  float *cs0 = cs[0], *cs1 = cs[1], *cs2 = cs[2], *cq0 = cq[0], *cq1 = cq[1], *cq2 = cq[2];
  float *mn0 = mn[0], *mn1 = mn[1], *mn2 = mn[2], *mx0 = mx[0], *mx1 = mx[1], *mx2 = mx[2];
  float *cu0 = cu[0], *cu1 = cu[1], *cu2 = cu[2];
  const __m256 q4 = _mm256_set1_ps(0.25f), h2 = _mm256_set1_ps(0.5f), mq4 = _mm256_set1_ps(-0.25f);
  for (; x + 8 <= w; x += 8) {
    __m256 c0[3], c1[3], c2[3];
    const std::size_t rr[3] = {r0 + std::size_t(x), r1 + std::size_t(x), r2 + std::size_t(x)};
    for (int j = 0; j < 3; ++j) {
      const __m256 r = _mm256_loadu_ps(R + rr[j]), g = _mm256_loadu_ps(G + rr[j]), b = _mm256_loadu_ps(Bc + rr[j]);
      if (ycocg) {
        c0[j] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(q4, r), _mm256_mul_ps(h2, g)), _mm256_mul_ps(q4, b));
        c1[j] = _mm256_sub_ps(_mm256_mul_ps(h2, r), _mm256_mul_ps(h2, b));
        c2[j] = _mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(mq4, r), _mm256_mul_ps(h2, g)), _mm256_mul_ps(q4, b));
      } else {
        c0[j] = r;
        c1[j] = g;
        c2[j] = b;
      }
    }
    col8(c0[0], c0[1], c0[2], cs0 + x, cq0 + x, mn0 + x, mx0 + x);
    col8(c1[0], c1[1], c1[2], cs1 + x, cq1 + x, mn1 + x, mx1 + x);
    col8(c2[0], c2[1], c2[2], cs2 + x, cq2 + x, mn2 + x, mx2 + x);
    _mm256_storeu_ps(cu0 + x, c0[1]);
    _mm256_storeu_ps(cu1 + x, c1[1]);
    _mm256_storeu_ps(cu2 + x, c2[1]);
  }
  return x;
}

__attribute__((target("avx2"))) int taa_box_avx2(int x, int w, bool ycocg, float gamma, const float* cs,
                                                 const float* cq, const float* cmn, const float* cmx, const float* cur,
                                                 float* blo, float* bhi) {
  const __m256 ninth = _mm256_set1_ps(1.0f / 9.0f), g4 = _mm256_set1_ps(gamma), zero = _mm256_setzero_ps();
  for (; x + 8 <= w; x += 8) {
    const __m256 mn0 = _mm256_loadu_ps(cmn + x), mn1 = _mm256_loadu_ps(cmn + x + 1), mn2 = _mm256_loadu_ps(cmn + x + 2);
    const __m256 mx0 = _mm256_loadu_ps(cmx + x), mx1 = _mm256_loadu_ps(cmx + x + 1), mx2 = _mm256_loadu_ps(cmx + x + 2);
    __m256 lo = _mm256_min_ps(_mm256_min_ps(mn2, mn1), mn0);  // std::min(mn0, std::min(mn1, mn2))
    __m256 hi = _mm256_max_ps(_mm256_max_ps(mx2, mx1), mx0);
    if (ycocg) {
      const __m256 mean =
          _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(_mm256_loadu_ps(cs + x), _mm256_loadu_ps(cs + x + 1)),
                                      _mm256_loadu_ps(cs + x + 2)),
                        ninth);
      const __m256 m2 = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(_mm256_loadu_ps(cq + x), _mm256_loadu_ps(cq + x + 1)),
                                                    _mm256_loadu_ps(cq + x + 2)),
                                      ninth);
      const __m256 var = _mm256_max_ps(_mm256_sub_ps(m2, _mm256_mul_ps(mean, mean)), zero);  // std::max(0, t)
      const __m256 sd = _mm256_mul_ps(g4, _mm256_sqrt_ps(var));
      const __m256 c = _mm256_loadu_ps(cur + x);
      lo = _mm256_max_ps(_mm256_min_ps(c, _mm256_sub_ps(mean, sd)), lo);  // std::max(lo, std::min(mean - sd, cur))
      hi = _mm256_min_ps(_mm256_max_ps(c, _mm256_add_ps(mean, sd)), hi);  // std::min(hi, std::max(mean + sd, cur))
    }
    _mm256_storeu_ps(blo + x, lo);
    _mm256_storeu_ps(bhi + x, hi);
  }
  return x;
}

__attribute__((target("avx2"))) int taa_clip_avx2(int x, int w, bool ycocg, float a, const float* const hv[3],
                                                  const float* okr, const float* const lo[3], const float* const hi[3],
                                                  const float* cr, const float* cg, const float* cb, float* nr,
                                                  float* ng, float* nb) {
  const float *h0 = hv[0], *h1 = hv[1], *h2_ = hv[2];
  const float *lo0 = lo[0], *lo1 = lo[1], *lo2 = lo[2], *hi0 = hi[0], *hi1 = hi[1], *hi2 = hi[2];
  const __m256 q4 = _mm256_set1_ps(0.25f), h2 = _mm256_set1_ps(0.5f), mq4 = _mm256_set1_ps(-0.25f);
  const __m256 one = _mm256_set1_ps(1.0f), big = _mm256_set1_ps(kMax), zero = _mm256_setzero_ps();
  const __m256 t5 = _mm256_set1_ps(1e-5f), t30 = _mm256_set1_ps(1e-30f), av = _mm256_set1_ps(a);
  for (; x + 8 <= w; x += 8) {
    const __m256 v0 = _mm256_loadu_ps(h0 + x), v1 = _mm256_loadu_ps(h1 + x), v2 = _mm256_loadu_ps(h2_ + x);
    const __m256 l0 = _mm256_loadu_ps(lo0 + x), l1 = _mm256_loadu_ps(lo1 + x), l2 = _mm256_loadu_ps(lo2 + x);
    const __m256 u0 = _mm256_loadu_ps(hi0 + x), u1 = _mm256_loadu_ps(hi1 + x), u2 = _mm256_loadu_ps(hi2 + x);
    __m256 s0, s1, s2;
    if (ycocg) {
      s0 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(q4, v0), _mm256_mul_ps(h2, v1)), _mm256_mul_ps(q4, v2));
      s1 = _mm256_sub_ps(_mm256_mul_ps(h2, v0), _mm256_mul_ps(h2, v2));
      s2 = _mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(mq4, v0), _mm256_mul_ps(h2, v1)), _mm256_mul_ps(q4, v2));
      const __m256 c0 = _mm256_mul_ps(h2, _mm256_add_ps(l0, u0)), c1 = _mm256_mul_ps(h2, _mm256_add_ps(l1, u1)),
                   c2 = _mm256_mul_ps(h2, _mm256_add_ps(l2, u2));
      const __m256 d0 = _mm256_sub_ps(s0, c0), d1 = _mm256_sub_ps(s1, c1), d2 = _mm256_sub_ps(s2, c2);
      const __m256 e0 = _mm256_mul_ps(h2, _mm256_sub_ps(u0, l0)), e1 = _mm256_mul_ps(h2, _mm256_sub_ps(u1, l1)),
                   e2 = _mm256_mul_ps(h2, _mm256_sub_ps(u2, l2));
      const __m256 tol = _mm256_add_ps(_mm256_mul_ps(t5, _mm256_add_ps(fabs8(c0), e0)), t30);
      const __m256 a0 = fabs8(d0), a1 = fabs8(d1), a2 = fabs8(d2);
      __m256 ratio = one;
      // std::max(ratio, q) = _mm256_max_ps(q, ratio)
      ratio = sel8(_mm256_and_ps(cmpgt8(e0, tol), cmpgt8(a0, e0)), _mm256_max_ps(_mm256_div_ps(a0, e0), ratio), ratio);
      ratio = sel8(_mm256_and_ps(cmpgt8(e1, tol), cmpgt8(a1, e1)), _mm256_max_ps(_mm256_div_ps(a1, e1), ratio), ratio);
      ratio = sel8(_mm256_and_ps(cmpgt8(e2, tol), cmpgt8(a2, e2)), _mm256_max_ps(_mm256_div_ps(a2, e2), ratio), ratio);
      const __m256 scale = _mm256_and_ps(cmpgt8(ratio, one), cmple8(ratio, big));
      s0 = sel8(scale, _mm256_add_ps(c0, _mm256_div_ps(d0, ratio)), s0);
      s1 = sel8(scale, _mm256_add_ps(c1, _mm256_div_ps(d1, ratio)), s1);
      s2 = sel8(scale, _mm256_add_ps(c2, _mm256_div_ps(d2, ratio)), s2);
    } else {
      s0 = v0;
      s1 = v1;
      s2 = v2;
    }
    s0 = clamp8(s0, l0, u0);
    s1 = clamp8(s1, l1, u1);
    s2 = clamp8(s2, l2, u2);
    __m256 k0, k1, k2;
    if (ycocg) {
      const __m256 t = _mm256_sub_ps(s0, s2);
      k0 = _mm256_add_ps(t, s1);
      k1 = _mm256_add_ps(s0, s2);
      k2 = _mm256_sub_ps(t, s1);
    } else {
      k0 = s0;
      k1 = s1;
      k2 = s2;
    }
    const __m256 ok = cmpneq8(_mm256_loadu_ps(okr + x), zero);
    const __m256 q0 = _mm256_loadu_ps(cr + x), q1 = _mm256_loadu_ps(cg + x), q2 = _mm256_loadu_ps(cb + x);
    const __m256 o0 = _mm256_add_ps(k0, _mm256_mul_ps(av, _mm256_sub_ps(q0, k0)));
    const __m256 o1 = _mm256_add_ps(k1, _mm256_mul_ps(av, _mm256_sub_ps(q1, k1)));
    const __m256 o2 = _mm256_add_ps(k2, _mm256_mul_ps(av, _mm256_sub_ps(q2, k2)));
    _mm256_storeu_ps(nr + x, sel8(_mm256_and_ps(ok, cmple8(fabs8(o0), big)), o0, q0));
    _mm256_storeu_ps(ng + x, sel8(_mm256_and_ps(ok, cmple8(fabs8(o1), big)), o1, q1));
    _mm256_storeu_ps(nb + x, sel8(_mm256_and_ps(ok, cmple8(fabs8(o2), big)), o2, q2));
  }
  return x;
}

__attribute__((target("avx2"))) void taa_lookup_cr_avx2(int w, int h, std::size_t n, const float* H, const float* px,
                                                        const float* py, const std::uint8_t* inside, float* h0,
                                                        float* h1, float* h2, float* okr) {
  // Per pixel: whether it has a history sample, and for an interior one (no clamped tap)
  // its weights and the first tap.
  struct Tap {
    bool ok, interior;
    float wx[4], wy[4];
    const float* base;
  };
  auto prepare = [&](int x, Tap& t) {
    t.ok = t.interior = false;
    const float fx = px[x], fy = py[x];
    if (!inside[x] || !(fx >= -0.5f && fy >= -0.5f && fx <= float(w) - 0.5f && fy <= float(h) - 0.5f)) return;
    t.ok = true;
    const int ix = floor_int(fx), iy = floor_int(fy);
    const int bx = ix - 1, by = iy - 1;
    if (!(bx >= 0 && by >= 0 && bx + 3 < w && by + 3 < h)) return;
    t.interior = true;
    cr_weights(fx - float(ix), t.wx);
    cr_weights(fy - float(iy), t.wy);
    t.base = H + std::size_t(by) * std::size_t(w) + std::size_t(bx);
  };
  auto single = [&](int x) {
    float hv[3] = {0, 0, 0};
    const bool ok = inside[x] && catmull_rom_planar(H, w, h, n, px[x], py[x], hv);
    h0[x] = hv[0];
    h1[x] = hv[1];
    h2[x] = hv[2];
    okr[x] = ok ? 1.0f : 0.0f;
  };
  int x = 0;
  for (; x + 2 <= w; x += 2) {
    Tap a, b;
    prepare(x, a);
    prepare(x + 1, b);
    if (!(a.interior && b.interior)) {
      single(x);
      single(x + 1);
      continue;
    }
    // Two pixels side by side, pixel x in the low 128-bit half: per half, the
    // operations of catmull_rom_planar's SSE2 path.
    const __m256 wy[4] = {_mm256_setr_m128(_mm_set1_ps(a.wy[0]), _mm_set1_ps(b.wy[0])),
                          _mm256_setr_m128(_mm_set1_ps(a.wy[1]), _mm_set1_ps(b.wy[1])),
                          _mm256_setr_m128(_mm_set1_ps(a.wy[2]), _mm_set1_ps(b.wy[2])),
                          _mm256_setr_m128(_mm_set1_ps(a.wy[3]), _mm_set1_ps(b.wy[3]))};
    const __m256 wx = _mm256_setr_m128(_mm_loadu_ps(a.wx), _mm_loadu_ps(b.wx));
    __m256 acc[3];
    for (int c = 0; c < 3; ++c) {
      const float* pa = a.base + std::size_t(c) * n;
      const float* pb = b.base + std::size_t(c) * n;
      __m256 s = _mm256_mul_ps(wy[0], _mm256_loadu2_m128(pb, pa));
      for (int j = 1; j < 4; ++j) {
        const std::size_t o = std::size_t(j) * std::size_t(w);
        s = _mm256_add_ps(s, _mm256_mul_ps(wy[j], _mm256_loadu2_m128(pb + o, pa + o)));
      }
      acc[c] = _mm256_mul_ps(s, wx);
    }
    // _MM_TRANSPOSE4_PS per half, the fourth row 0; then (r0 + r1) + (r2 + r3).
    const __m256 zero = _mm256_setzero_ps();
    const __m256 t0 = _mm256_unpacklo_ps(acc[0], acc[1]), t2 = _mm256_unpacklo_ps(acc[2], zero);
    const __m256 t1 = _mm256_unpackhi_ps(acc[0], acc[1]), t3 = _mm256_unpackhi_ps(acc[2], zero);
    const __m256 r0 = _mm256_shuffle_ps(t0, t2, 0x44), r1 = _mm256_shuffle_ps(t0, t2, 0xEE);
    const __m256 r2 = _mm256_shuffle_ps(t1, t3, 0x44), r3 = _mm256_shuffle_ps(t1, t3, 0xEE);
    const __m256 sum = _mm256_add_ps(_mm256_add_ps(r0, r1), _mm256_add_ps(r2, r3));
    alignas(32) float o8[8];
    _mm256_store_ps(o8, sum);
    h0[x] = o8[0];
    h1[x] = o8[1];
    h2[x] = o8[2];
    okr[x] = 1.0f;
    h0[x + 1] = o8[4];
    h1[x + 1] = o8[5];
    h2[x + 1] = o8[6];
    okr[x + 1] = 1.0f;
  }
  for (; x < w; ++x) single(x);
}

}  // namespace mcr::detail

#else

namespace mcr::detail {
bool taa_avx2_available() { return false; }
int taa_stats_avx2(int x, int, bool, const float*, const float*, const float*, std::size_t, std::size_t, std::size_t,
                   float* const*, float* const*, float* const*, float* const*, float* const*) {
  return x;
}
int taa_box_avx2(int x, int, bool, float, const float*, const float*, const float*, const float*, const float*, float*,
                 float*) {
  return x;
}
int taa_clip_avx2(int x, int, bool, float, const float* const*, const float*, const float* const*, const float* const*,
                  const float*, const float*, const float*, float*, float*, float*) {
  return x;
}
void taa_lookup_cr_avx2(int, int, std::size_t, const float*, const float*, const float*, const std::uint8_t*, float*,
                        float*, float*, float*) {}
}  // namespace mcr::detail

#endif
