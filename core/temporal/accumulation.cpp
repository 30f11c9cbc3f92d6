#include "temporal/accumulation.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "util/error.h"
#include "util/parallel.h"
#include "util/avx2_shuffles.h"
#include "util/isa.h"

namespace mcr {

void AccumulationBuffer::reset() {
  value_ = Image();
  next_ = Image();
  count_.clear();
  next_count_.clear();
}

void AccumulationBuffer::begin(const Reprojection& r, const Image& current) {
  const int w = current.width(), h = current.height(), ch = current.channels();
  if (ch > 8) throw Error(Errc::Internal, "accumulation: at most 8 channels");
  usable_ = r.has_history && !r.cut && value_.width() == w && value_.height() == h && value_.channels() == ch &&
            r.width == w && r.height == h && count_.size() == current.pixel_count();
  if (next_.width() != w || next_.height() != h || next_.channels() != ch) next_ = Image(w, h, ch);
  next_count_.resize(current.pixel_count());  // every entry is rewritten by row()
}

namespace {

// Row y of the blend for 3 channels (every BMFR buffer): the generic loop below with the
// channel count fixed, so the history and the blend stay in registers. Same operations in
// the same order.
// Pixels [xb, w) of the row.
// Rec. 709 luminance weights in float (the guards' luminance; image/luminance.h in double).
constexpr float kY0 = 0.2126f, kY1 = 0.7152f, kY2 = 0.0722f;

// RGB scaled alike so that its luminance is at most bound (the guards' cut).
inline void cut_to(float bound, float& r, float& g, float& b) {
  const float yl = kY0 * r + kY1 * g + kY2 * b;
  if (yl > bound) {
    const float sc = bound / yl;
    r *= sc;
    g *= sc;
    b *= sc;
  }
}

void row3(int y, const Reprojection& r, const float* crow_all, const float* hist, const float* hcount, float af,
          int w, float* orow, float* ncount, const AccumulationGuards& g, int xb = 0) {
  const float* lim = g.limit ? g.limit + std::size_t(y) * std::size_t(w) : nullptr;
  const float* limf = g.limit && g.limit_fresh ? g.limit_fresh + std::size_t(y) * std::size_t(w) : nullptr;
  const float* afl = g.alpha_floor ? g.alpha_floor + std::size_t(y) * std::size_t(w) : nullptr;
  const float* cap = g.history_cap ? g.history_cap + std::size_t(y) * std::size_t(w) : nullptr;
  const float hf = g.history_factor;
  const float* crow = crow_all + std::size_t(y) * std::size_t(w) * 3;
  const std::uint8_t* taps = r.taps.data() + std::size_t(y) * std::size_t(w);
  const float* pxs = r.prev_x.data() + std::size_t(y) * std::size_t(w);
  const float* pys = r.prev_y.data() + std::size_t(y) * std::size_t(w);
  const std::size_t sw = std::size_t(w);
  for (int x = xb; x < w; ++x) {
    const float* c = crow + std::size_t(x) * 3;
    float* o = orow + std::size_t(x) * 3;
    float c0 = c[0], c1 = c[1], c2 = c[2];
    const bool finite = ((c0 - c0) + (c1 - c1) + (c2 - c2)) == 0.0f;  // x - x is NaN for NaN/Inf
    float h0 = 0, h1 = 0, h2 = 0, n = 0;
    bool have = false;
    const std::uint8_t mask = hist ? taps[x] : 0;
    if (mask) {
      const float px = pxs[x], py = pys[x];
      const int x0 = floor_int(px), y0 = floor_int(py);
      const float fx = px - float(x0), fy = py - float(y0);
      const float wt[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
      const std::size_t t0 = std::size_t(y0) * sw + std::size_t(x0);
      const std::size_t tt[4] = {t0, t0 + 1, t0 + sw, t0 + sw + 1};
      float sum = 0, cnt = 0;
      for (int k = 0; k < 4; ++k) {
        if (!(mask & (1u << k)) || wt[k] <= 0.0f) continue;
        const std::size_t t = tt[k];
        const float tc = hcount[t];
        if (!(tc > 0.0f)) continue;
        sum += wt[k];
        cnt += wt[k] * tc;
        const float* hp = hist + t * 3;
        h0 += wt[k] * hp[0];
        h1 += wt[k] * hp[1];
        h2 += wt[k] * hp[2];
      }
      if (sum > 1e-6f) {
        const float inv = 1.0f / sum;
        h0 *= inv;
        h1 *= inv;
        h2 *= inv;
        n = std::max(1.0f, float(int(cnt * inv + 0.5f)));
        have = true;
      }
    }
    if (cap && have) cut_to(std::max(cap[x], 0.0f), h0, h1, h2);  // no brighter than the current neighbourhood
    if (lim && finite) {
      const float yh = have ? kY0 * h0 + kY1 * h1 + kY2 * h2 : 0.0f;
      const float l = (have || !limf) ? lim[x] : limf[x];
      cut_to(std::max(std::max(l, hf * yh), 0.0f), c0, c1, c2);
    }
    if (!finite) {
      o[0] = have ? h0 : 0.0f;  // invalid without history: value 0, count 0
      o[1] = have ? h1 : 0.0f;
      o[2] = have ? h2 : 0.0f;
      ncount[x] = have ? n : 0.0f;
      continue;
    }
    if (!have) {
      o[0] = c0;
      o[1] = c1;
      o[2] = c2;
      ncount[x] = 1.0f;
      continue;
    }
    const float wn = std::max(1.0f / (n + 1.0f), afl ? std::max(af, afl[x]) : af);
    o[0] = h0 + wn * (c0 - h0);
    o[1] = h1 + wn * (c1 - h1);
    o[2] = h2 + wn * (c2 - h2);
    ncount[x] = std::min(n + 1.0f, 65535.0f);
  }
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MCR_ACC_AVX2 1
// row3 for 8 pixels at a time (AVX2 without FMA: every lane does the float operations of
// row3 in the same order, so the results are the same bit for bit). The taps are
// gathered; a tap that row3 skips leaves the sums untouched (blend, not + 0).
// cut_to for 8 pixels, where `on`: the same float operations in the same order.
__attribute__((target("avx2"), always_inline)) inline __m256 luminance8(__m256 r, __m256 g, __m256 b) {
  return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(kY0), r), _mm256_mul_ps(_mm256_set1_ps(kY1), g)),
                       _mm256_mul_ps(_mm256_set1_ps(kY2), b));
}
__attribute__((target("avx2"), always_inline)) inline void cut_to8(__m256 bound, __m256 on, __m256& r, __m256& g,
                                                                    __m256& b) {
  const __m256 yl = luminance8(r, g, b);
  const __m256 cut = _mm256_and_ps(on, _mm256_cmp_ps(yl, bound, _CMP_GT_OQ));
  const __m256 sc = _mm256_div_ps(bound, yl);
  r = _mm256_blendv_ps(r, _mm256_mul_ps(r, sc), cut);
  g = _mm256_blendv_ps(g, _mm256_mul_ps(g, sc), cut);
  b = _mm256_blendv_ps(b, _mm256_mul_ps(b, sc), cut);
}

__attribute__((target("avx2"))) void row3_avx2(int y, const Reprojection& r, const float* crow_all, const float* hist,
                                               const float* hcount, float af, int w, float* orow, float* ncount,
                                               const AccumulationGuards& g) {
  const std::size_t rb = std::size_t(y) * std::size_t(w);
  const float* lim = g.limit ? g.limit + rb : nullptr;
  const float* limf = g.limit && g.limit_fresh ? g.limit_fresh + rb : nullptr;
  const float* afl = g.alpha_floor ? g.alpha_floor + rb : nullptr;
  const float* cap = g.history_cap ? g.history_cap + rb : nullptr;
  const __m256 hfv = _mm256_set1_ps(g.history_factor);
  const float* crow = crow_all + rb * 3;
  const std::uint8_t* taps = r.taps.data() + rb;
  const float* pxs = r.prev_x.data() + rb;
  const float* pys = r.prev_y.data() + rb;
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), half = _mm256_set1_ps(0.5f),
               tiny = _mm256_set1_ps(1e-6f), afv = _mm256_set1_ps(af), cmax = _mm256_set1_ps(65535.0f);
  const __m256i iw = _mm256_set1_epi32(w), three = _mm256_set1_epi32(3);
  const __m256i last8 = _mm256_set1_epi32(int(std::size_t(w) * std::size_t(r.height)) - 3);
  const std::size_t last = std::size_t(w) * std::size_t(r.height) - 1;
  const __m256i off[4] = {_mm256_setzero_si256(), _mm256_set1_epi32(1), iw, _mm256_set1_epi32(w + 1)};
  int x = 0;
  for (; x + 8 <= w; x += 8) {
    const float* c = crow + std::size_t(x) * 3;
    __m256 c0, c1, c2;
    load_rgb8(c, c0, c1, c2);
    const __m256 finite =
        _mm256_cmp_ps(_mm256_add_ps(_mm256_add_ps(_mm256_sub_ps(c0, c0), _mm256_sub_ps(c1, c1)), _mm256_sub_ps(c2, c2)),
                      zero, _CMP_EQ_OQ);
    __m256 h0 = zero, h1 = zero, h2 = zero, n = zero, have = zero;
    std::uint64_t m8 = 0;
    if (hist) std::memcpy(&m8, taps + x, 8);
    if (m8) {
      // The history rows y and y + 1 some pixels ahead (taps follow the pixel for small
      // motion): their first touch is otherwise a cache miss inside a gather.
      const std::size_t ahead = std::min(rb + std::size_t(x) + 64, last);
      const std::size_t below = std::min(ahead + std::size_t(w), last);
      _mm_prefetch(reinterpret_cast<const char*>(hcount + ahead), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(hcount + below), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(hist + ahead * 3), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(hist + ahead * 3 + 16), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(hist + below * 3), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(hist + below * 3 + 16), _MM_HINT_T0);
      const __m256i mask = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(m8)));
      const __m256 px = _mm256_loadu_ps(pxs + x), py = _mm256_loadu_ps(pys + x);
      // floor_int: truncate, minus one where that rounded up.
      __m256i x0 = _mm256_cvttps_epi32(px), y0 = _mm256_cvttps_epi32(py);
      x0 = _mm256_add_epi32(x0, _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(x0), px, _CMP_GT_OQ)));
      y0 = _mm256_add_epi32(y0, _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(y0), py, _CMP_GT_OQ)));
      const __m256 fx = _mm256_sub_ps(px, _mm256_cvtepi32_ps(x0)), fy = _mm256_sub_ps(py, _mm256_cvtepi32_ps(y0));
      const __m256 gx = _mm256_sub_ps(one, fx), gy = _mm256_sub_ps(one, fy);
      const __m256 wt[4] = {_mm256_mul_ps(gx, gy), _mm256_mul_ps(fx, gy), _mm256_mul_ps(gx, fy), _mm256_mul_ps(fx, fy)};
      const __m256i t0 = _mm256_add_epi32(_mm256_mullo_epi32(y0, iw), x0);
      __m256 sum = zero, cnt = zero;
      // Taps in pairs (k, k + 1) on one history row: per lane one 8-float load covers
      // both taps' RGB (a transpose makes them planes); the counts are gathered.
      for (int k = 0; k < 4; k += 2) {
        __m256 on[2];
        for (int j = 0; j < 2; ++j) {
          const __m256i bit = _mm256_set1_epi32(1 << (k + j));
          on[j] = _mm256_and_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(mask, bit), bit)),
                                _mm256_cmp_ps(wt[k + j], zero, _CMP_GT_OQ));
        }
        const __m256 any = _mm256_or_ps(on[0], on[1]);
        if (_mm256_testz_ps(any, any)) continue;
        const __m256i t = _mm256_add_epi32(t0, off[k]);
        const __m256 tc[2] = {_mm256_mask_i32gather_ps(zero, hcount, t, on[0], 4),
                              _mm256_mask_i32gather_ps(zero, hcount, _mm256_add_epi32(t, off[1]), on[1], 4)};
        const __m256 use[2] = {_mm256_and_ps(on[0], _mm256_cmp_ps(tc[0], zero, _CMP_GT_OQ)),
                               _mm256_and_ps(on[1], _mm256_cmp_ps(tc[1], zero, _CMP_GT_OQ))};
        __m256 v[8];
        const __m256i ti = _mm256_and_si256(t, _mm256_castps_si256(any));  // lanes off read pixel 0
        // 8 floats from pixel ti stay inside the image up to ti = n - 3; past that (the
        // last two pixels) the taps are gathered.
        if (_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(ti, last8))) == 0) {
          alignas(32) int idx[8];
          _mm256_store_si256(reinterpret_cast<__m256i*>(idx), ti);
          for (int l = 0; l < 8; ++l) v[l] = _mm256_loadu_ps(hist + std::size_t(idx[l]) * 3);
          transpose8(v);
        } else {
          for (int j = 0; j < 2; ++j) {
            const __m256i t3 = _mm256_mullo_epi32(_mm256_add_epi32(t, off[j]), three);
            for (int c = 0; c < 3; ++c) v[3 * j + c] = _mm256_mask_i32gather_ps(zero, hist + c, t3, use[j], 4);
          }
        }
        for (int j = 0; j < 2; ++j) {
          const __m256 wk = wt[k + j], u = use[j];
          sum = _mm256_blendv_ps(sum, _mm256_add_ps(sum, wk), u);
          cnt = _mm256_blendv_ps(cnt, _mm256_add_ps(cnt, _mm256_mul_ps(wk, tc[j])), u);
          h0 = _mm256_blendv_ps(h0, _mm256_add_ps(h0, _mm256_mul_ps(wk, v[3 * j])), u);
          h1 = _mm256_blendv_ps(h1, _mm256_add_ps(h1, _mm256_mul_ps(wk, v[3 * j + 1])), u);
          h2 = _mm256_blendv_ps(h2, _mm256_add_ps(h2, _mm256_mul_ps(wk, v[3 * j + 2])), u);
        }
      }
      have = _mm256_cmp_ps(sum, tiny, _CMP_GT_OQ);
      const __m256 inv = _mm256_div_ps(one, sum);
      h0 = _mm256_and_ps(have, _mm256_mul_ps(h0, inv));
      h1 = _mm256_and_ps(have, _mm256_mul_ps(h1, inv));
      h2 = _mm256_and_ps(have, _mm256_mul_ps(h2, inv));
      // std::max(1.0f, float(int(cnt * inv + 0.5f)))
      const __m256 rc = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(cnt, inv), half)));
      n = _mm256_and_ps(have, _mm256_max_ps(rc, one));
    }
    if (cap) cut_to8(_mm256_max_ps(zero, _mm256_loadu_ps(cap + x)), have, h0, h1, h2);  // row3's history cap
    if (lim) {  // row3's guard: the same operations (std::max(a, b) = max_ps(b, a))
      const __m256 yh = _mm256_and_ps(have, luminance8(h0, h1, h2));
      const __m256 lv = _mm256_loadu_ps(lim + x);
      const __m256 l = limf ? _mm256_blendv_ps(_mm256_loadu_ps(limf + x), lv, have) : lv;
      cut_to8(_mm256_max_ps(zero, _mm256_max_ps(_mm256_mul_ps(hfv, yh), l)), finite, c0, c1, c2);
    }
    // Finite with history: blend; finite without: the new value (count 1); non-finite:
    // the history (or 0, count 0).
    const __m256 afx = afl ? _mm256_max_ps(_mm256_loadu_ps(afl + x), afv) : afv;  // std::max(af, afl)
    const __m256 wn = _mm256_max_ps(afx, _mm256_div_ps(one, _mm256_add_ps(n, one)));  // std::max(1/(n+1), af)
    const __m256 blend = _mm256_and_ps(finite, have), fresh = _mm256_andnot_ps(have, finite);
    const __m256 o0 = _mm256_blendv_ps(_mm256_blendv_ps(h0, c0, fresh), _mm256_add_ps(h0, _mm256_mul_ps(wn, _mm256_sub_ps(c0, h0))), blend);
    const __m256 o1 = _mm256_blendv_ps(_mm256_blendv_ps(h1, c1, fresh), _mm256_add_ps(h1, _mm256_mul_ps(wn, _mm256_sub_ps(c1, h1))), blend);
    const __m256 o2 = _mm256_blendv_ps(_mm256_blendv_ps(h2, c2, fresh), _mm256_add_ps(h2, _mm256_mul_ps(wn, _mm256_sub_ps(c2, h2))), blend);
    const __m256 nc = _mm256_blendv_ps(_mm256_blendv_ps(n, one, fresh), _mm256_min_ps(_mm256_add_ps(n, one), cmax), blend);
    _mm256_storeu_ps(ncount + x, nc);
    store_rgb8(orow + std::size_t(x) * 3, o0, o1, o2);
  }
  row3(y, r, crow_all, hist, hcount, af, w, orow, ncount, g, x);
}

#endif

}  // namespace

void AccumulationBuffer::row(int y, const Reprojection& r, const Image& current, double alpha,
                             const AccumulationGuards& g) {
  const int w = current.width(), h = current.height(), ch = current.channels();
  if (ch == 3) {
#ifdef MCR_ACC_AVX2
    if (isa_at_least(Isa::Avx2)) {
      row3_avx2(y, r, current.data(), usable_ ? value_.data() : nullptr, usable_ ? count_.data() : nullptr, float(alpha),
                w, next_.data() + std::size_t(y) * std::size_t(w) * 3, next_count_.data() + std::size_t(y) * std::size_t(w), g);
      return;
    }
#endif
    row3(y, r, current.data(), usable_ ? value_.data() : nullptr, usable_ ? count_.data() : nullptr, float(alpha), w,
         next_.data() + std::size_t(y) * std::size_t(w) * 3, next_count_.data() + std::size_t(y) * std::size_t(w), g);
    return;
  }
  if (g.any()) throw Error(Errc::Internal, "accumulation: guards need 3 channels");
  const float* hist = usable_ ? value_.data() : nullptr;
  const float* hcount = usable_ ? count_.data() : nullptr;
  const float af = float(alpha);
  const float* crow = current.data() + std::size_t(y) * w * ch;
  float* orow = next_.data() + std::size_t(y) * w * ch;
  float* ncount = next_count_.data() + std::size_t(y) * w;
  for (int x = 0; x < w; ++x) {
    const std::size_t i = std::size_t(y) * w + x;
    const float* c = crow + std::size_t(x) * ch;
    float* o = orow + std::size_t(x) * ch;
    bool finite = true;
    for (int k = 0; k < ch; ++k) finite = finite && std::isfinite(c[k]);
    float hv[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    float n = 0;
    bool have = false;
    const std::uint8_t mask = hist ? r.taps[i] : 0;
    if (mask) {
      // Bilinear taps that passed the tests and hold a valid history, value and count in
      // one go, normalised by the kept weights only.
      const float px = r.prev_x[i], py = r.prev_y[i];
      const int x0 = floor_int(px), y0 = floor_int(py);
      const float fx0 = float(x0), fy0 = float(y0);
      const float fx = px - fx0, fy = py - fy0;
      const float wt[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
      float sum = 0, cnt = 0;
      for (int k = 0; k < 4; ++k) {
        if (!(mask & (1u << k)) || wt[k] <= 0.0f) continue;
        const std::size_t t = std::size_t(y0 + (k >> 1)) * std::size_t(w) + std::size_t(x0 + (k & 1));
        const float tc = hcount[t];
        if (!(tc > 0.0f)) continue;
        sum += wt[k];
        cnt += wt[k] * tc;
        const float* hp = hist + t * std::size_t(ch);
        for (int k2 = 0; k2 < ch; ++k2) hv[k2] += wt[k] * hp[k2];
      }
      if (sum > 1e-6f) {
        const float inv = 1.0f / sum;
        for (int k2 = 0; k2 < ch; ++k2) hv[k2] *= inv;
        n = std::max(1.0f, float(int(cnt * inv + 0.5f)));  // counts are >= 0: round half up
        have = true;
      }
    }
    if (!finite) {
      if (have) {
        std::copy(hv, hv + ch, o);
        ncount[x] = n;
      } else {  // invalid, value 0, count 0
        std::fill(o, o + ch, 0.0f);
        ncount[x] = 0.0f;
      }
      continue;
    }
    if (!have) {
      std::copy(c, c + ch, o);
      ncount[x] = 1.0f;
      continue;
    }
    const float wn = std::max(1.0f / (n + 1.0f), af);
    for (int k = 0; k < ch; ++k) o[k] = hv[k] + wn * (c[k] - hv[k]);
    ncount[x] = std::min(n + 1.0f, 65535.0f);
  }
  (void)h;
}

void AccumulationBuffer::finish() {
  std::swap(value_, next_);
  std::swap(count_, next_count_);
}

const Image& AccumulationBuffer::accumulate(const Reprojection& r, const Image& current, double alpha, int nthreads,
                                            const AccumulationGuards& guards) {
  begin(r, current);
  parallel_rows(0, current.height(), nthreads, [&](int y) { row(y, r, current, alpha, guards); });
  finish();
  return value_;
}

void TemporalAccumulator::reset() {
  geometry_.reset();
  buffer_.reset();
  reprojection_ = Reprojection();
}

const Image& TemporalAccumulator::accumulate(const Frame& frame, const Image& colour, int nthreads) {
  const Image& pos = frame.image(Role::Position, Prefer::Geometry);
  const Image& nrm = frame.image(Role::Normal, Prefer::Geometry);
  const Pass* mp = frame.find(Role::Motion);
  return accumulate(colour, pos, nrm, mp ? &mp->image : nullptr, nthreads);
}

const Image& TemporalAccumulator::accumulate(const Frame& frame, const Image& colour,
                                             const std::function<void(int)>& before_row, int nthreads) {
  const Image& pos = frame.image(Role::Position, Prefer::Geometry);
  const Image& nrm = frame.image(Role::Normal, Prefer::Geometry);
  const Pass* mp = frame.find(Role::Motion);
  before_row_ = before_row ? &before_row : nullptr;
  try {
    const Image& out = accumulate(colour, pos, nrm, mp ? &mp->image : nullptr, nthreads);
    before_row_ = nullptr;
    return out;
  } catch (...) {
    before_row_ = nullptr;
    throw;
  }
}

const Image& TemporalAccumulator::accumulate(const Image& colour, const Image& position, const Image& normal,
                                             const Image* motion, int nthreads) {
  if (position.width() != colour.width() || position.height() != colour.height() ||
      normal.width() != colour.width() || normal.height() != colour.height())
    throw Error(Errc::SizeMismatch, "accumulation: colour, position and normal differ in size");
  if (position.channels() < 3 || normal.channels() < 3)
    throw Error(Errc::InvalidArgument, "accumulation: position and normal need 3 channels");
  // Reprojection and accumulation fused: row y is blended right after its taps are
  // decided (it reads only the previous frame's buffers). A camera cut is only known once
  // every row is done; the blend is then redone without history.
  Reprojection& r = reprojection_;
  geometry_.begin(position, normal, motion, r);
  buffer_.begin(r, colour);
  const int h = colour.height();
  row_lost_.assign(std::size_t(std::max(h, 0)), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    if (before_row_) (*before_row_)(y);
    row_lost_[std::size_t(y)] = geometry_.row(y, position, normal, motion, params_.reprojection, r);
    buffer_.row(y, r, colour, params_.alpha, guards_);
  });
  std::size_t lost = 0;
  for (std::size_t v : row_lost_) lost += v;
  if (geometry_.finish(params_.reprojection, r, lost)) {
    buffer_.begin(r, colour);
    parallel_rows(0, h, nthreads, [&](int y) { buffer_.row(y, r, colour, params_.alpha, guards_); });
  }
  buffer_.finish();
  return buffer_.value();
}

}  // namespace mcr
