#include "temporal/reprojection_avx2.h"

#include <algorithm>
#include <cmath>

#include "temporal/reprojection.h"

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#include <immintrin.h>

#include "util/avx2_shuffles.h"
#include "util/isa.h"

namespace mcr::detail {

bool tap_row_avx2_available() { return isa_at_least(Isa::Avx2); }

namespace {

struct V3 {
  __m256 x, y, z;
};

__attribute__((target("avx2"), always_inline)) inline V3 load3(const float* p) {
  V3 v;
  load_rgb8(p, v.x, v.y, v.z);
  return v;
}

// ((a - b)^2 summed left to right, as d2() in reprojection.cpp.
__attribute__((target("avx2"), always_inline)) inline __m256 dist2(const V3& a, const V3& b) {
  const __m256 dx = _mm256_sub_ps(a.x, b.x), dy = _mm256_sub_ps(a.y, b.y), dz = _mm256_sub_ps(a.z, b.z);
  return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
}

// All three finite (x - x is 0 for finite x, NaN otherwise).
__attribute__((target("avx2"), always_inline)) inline __m256 finite3(const V3& p) {
  const __m256 s = _mm256_add_ps(_mm256_add_ps(_mm256_sub_ps(p.x, p.x), _mm256_sub_ps(p.y, p.y)), _mm256_sub_ps(p.z, p.z));
  return _mm256_cmp_ps(s, _mm256_setzero_ps(), _CMP_EQ_OQ);
}

// 0 <= v < n, as a lane mask.
__attribute__((target("avx2"), always_inline)) inline __m256i in_range(__m256i v, __m256i n) {
  return _mm256_andnot_si256(_mm256_cmpgt_epi32(_mm256_setzero_si256(), v), _mm256_cmpgt_epi32(n, v));
}

}  // namespace

__attribute__((target("avx2"))) std::size_t tap_row_avx2(const TapRow& a, int x0, int x1) {
  const int w = a.w, h = a.h, y = a.y;
  const std::size_t rs = std::size_t(w) * 3;
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), inf = _mm256_set1_ps(INFINITY);
  const __m256 big = _mm256_set1_ps(1e7f), mtwo = _mm256_set1_ps(-2.0f), sign = _mm256_set1_ps(-0.0f);
  const __m256 thr2 = _mm256_set1_ps(a.thr2), cs2 = _mm256_set1_ps(a.cs2), eps6 = _mm256_set1_ps(1e-6f);
  const bool cs_pos = a.cs >= 0;
  const __m256i iw = _mm256_set1_epi32(w), ih = _mm256_set1_epi32(h), ione = _mm256_set1_epi32(1),
                lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i mstride = _mm256_mullo_epi32(lane, _mm256_set1_epi32(a.mch));
  const bool up = y > 0, down = y + 1 < h;
  const std::size_t last = std::size_t(w) * std::size_t(h) - 1;
  std::size_t lost = 0;
  for (int x = x0; x < x1; x += 8) {
    // Previous-frame position; non-finite or huge: far outside.
    __m256 px = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(x), lane));
    __m256 py = _mm256_set1_ps(float(y));
    if (a.mrow) {
      const float* m = a.mrow + std::size_t(x) * std::size_t(a.mch);
      __m256 mx, my;
      if (a.mch == 4) {
        load_xy4x8(m, mx, my);
      } else {
        mx = _mm256_i32gather_ps(m, mstride, 4);
        my = _mm256_i32gather_ps(m + 1, mstride, 4);
      }
      px = _mm256_add_ps(px, mx);
      py = _mm256_sub_ps(py, my);
    }
    const __m256 near = _mm256_and_ps(_mm256_cmp_ps(_mm256_andnot_ps(sign, px), big, _CMP_LE_OQ),
                                      _mm256_cmp_ps(_mm256_andnot_ps(sign, py), big, _CMP_LE_OQ));
    px = _mm256_blendv_ps(mtwo, px, near);
    py = _mm256_blendv_ps(mtwo, py, near);
    _mm256_storeu_ps(a.prev_x + x, px);
    _mm256_storeu_ps(a.prev_y + x, py);
    __m256i ix = _mm256_cvttps_epi32(px), iy = _mm256_cvttps_epi32(py);  // floor_int
    ix = _mm256_add_epi32(ix, _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(ix), px, _CMP_GT_OQ)));
    iy = _mm256_add_epi32(iy, _mm256_castps_si256(_mm256_cmp_ps(_mm256_cvtepi32_ps(iy), py, _CMP_GT_OQ)));
    // Tap k inside: column x0 + (k & 1) in [0, w), row y0 + (k >> 1) in [0, h).
    const __m256i ix1 = _mm256_add_epi32(ix, ione), iy1 = _mm256_add_epi32(iy, ione);
    const __m256i cx0 = in_range(ix, iw), cx1 = in_range(ix1, iw), cy0 = in_range(iy, ih), cy1 = in_range(iy1, ih);
    const __m256i ink[4] = {_mm256_and_si256(cx0, cy0), _mm256_and_si256(cx1, cy0), _mm256_and_si256(cx0, cy1),
                            _mm256_and_si256(cx1, cy1)};
    __m256i in = _mm256_setzero_si256();
    for (int k = 0; k < 4; ++k) in = _mm256_or_si256(in, _mm256_and_si256(ink[k], _mm256_set1_epi32(1 << k)));
    // This pixel's record: the squared normal length where position and normal are finite.
    const V3 pc = load3(a.prow + std::size_t(x) * 3), nc = load3(a.nrow + std::size_t(x) * 3);
    __m256 ncl;
    {
      const __m256 fin = _mm256_and_ps(finite3(pc), finite3(nc));
      const __m256 l =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nc.x, nc.x), _mm256_mul_ps(nc.y, nc.y)), _mm256_mul_ps(nc.z, nc.z));
      ncl = _mm256_blendv_ps(_mm256_set1_ps(NAN), l, fin);
      __m256 rec[8] = {pc.x, pc.y, pc.z, nc.x, nc.y, nc.z, ncl, zero};
      transpose8(rec);
      float* g = a.grow + std::size_t(x) * kGeoRecord;
      for (int l8 = 0; l8 < 8; ++l8) _mm256_storeu_ps(g + l8 * kGeoRecord, rec[l8]);
    }
    const __m256 live = _mm256_and_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(in, _mm256_setzero_si256())),
                                      _mm256_cmp_ps(ncl, ncl, _CMP_ORD_Q));
    __m256i mask = _mm256_setzero_si256();
    if (!_mm256_testz_ps(live, live)) {
      // The history records of rows y and y + 1 some pixels ahead (taps follow the pixel
      // for small motion): otherwise the first touch is a miss in the per-lane loads.
      {
        const std::size_t ahead = std::min(std::size_t(y) * std::size_t(w) + std::size_t(x) + 32, last);
        const std::size_t below = std::min(ahead + std::size_t(w), last);
        for (int l = 0; l < 4; ++l) {
          _mm_prefetch(reinterpret_cast<const char*>(a.hgeo + ahead * kGeoRecord + 16 * l), _MM_HINT_T0);
          _mm_prefetch(reinterpret_cast<const char*>(a.hgeo + below * kGeoRecord + 16 * l), _MM_HINT_T0);
        }
      }
      __m256 limit = thr2;
      if (a.relative) {
        // Footprint: larger of the horizontal and vertical distance to the nearer finite
        // neighbour (x - 1 and x + 1 exist here; rows only when inside the frame).
        const V3 l = load3(a.prow + std::size_t(x - 1) * 3), r = load3(a.prow + std::size_t(x + 1) * 3);
        __m256 fh = _mm256_blendv_ps(inf, dist2(pc, l), finite3(l));
        fh = _mm256_blendv_ps(fh, _mm256_min_ps(dist2(pc, r), fh), finite3(r));  // std::min(fh, d)
        __m256 fv = inf;
        if (up) {
          const V3 u = load3(a.prow + std::size_t(x) * 3 - rs);
          fv = _mm256_blendv_ps(inf, dist2(pc, u), finite3(u));
        }
        if (down) {
          const V3 d = load3(a.prow + std::size_t(x) * 3 + rs);
          fv = _mm256_blendv_ps(fv, _mm256_min_ps(dist2(pc, d), fv), finite3(d));
        }
        __m256 f = zero;
        f = _mm256_blendv_ps(f, _mm256_max_ps(fh, f), _mm256_cmp_ps(fh, inf, _CMP_LT_OQ));  // std::max(f, fh)
        f = _mm256_blendv_ps(f, _mm256_max_ps(fv, f), _mm256_cmp_ps(fv, inf, _CMP_LT_OQ));
        limit = _mm256_mul_ps(limit, f);
      }
      {
        const __m256 len2 =
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(pc.x, pc.x), _mm256_mul_ps(pc.y, pc.y)), _mm256_mul_ps(pc.z, pc.z));
        const __m256 fl = _mm256_mul_ps(eps6, _mm256_add_ps(one, _mm256_sqrt_ps(len2)));
        limit = _mm256_max_ps(_mm256_mul_ps(fl, fl), limit);  // std::max(limit, fl * fl)
      }
      const __m256 cbg = _mm256_cmp_ps(ncl, eps6, _CMP_LT_OQ);
      const __m256i t0 = _mm256_add_epi32(_mm256_mullo_epi32(iy, iw), ix);
      const __m256i off[4] = {_mm256_setzero_si256(), ione, iw, _mm256_add_epi32(iw, ione)};
      for (int k = 0; k < 4; ++k) {
        const __m256 on = _mm256_and_ps(live, _mm256_castsi256_ps(ink[k]));
        if (_mm256_testz_ps(on, on)) continue;
        // The tap's record per lane (lanes off read pixel 0), transposed to planes.
        const __m256i ti = _mm256_and_si256(_mm256_add_epi32(t0, off[k]), _mm256_castps_si256(on));
        alignas(32) int idx[8];
        _mm256_store_si256(reinterpret_cast<__m256i*>(idx), ti);
        __m256 rec[8];
        for (int l8 = 0; l8 < 8; ++l8) rec[l8] = _mm256_loadu_ps(a.hgeo + std::size_t(idx[l8]) * kGeoRecord);
        transpose8(rec);
        const V3 pp{rec[0], rec[1], rec[2]}, np{rec[3], rec[4], rec[5]};
        const __m256 npl = rec[6];
        const __m256 use = _mm256_and_ps(on, _mm256_cmp_ps(npl, npl, _CMP_ORD_Q));
        __m256 ok = _mm256_and_ps(use, _mm256_cmp_ps(dist2(pc, pp), limit, _CMP_LE_OQ));
        const __m256 pbg = _mm256_cmp_ps(npl, eps6, _CMP_LT_OQ);
        // cos >= cs without square roots: d >= cs |a||b|; both background: agree.
        const __m256 d =
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nc.x, np.x), _mm256_mul_ps(nc.y, np.y)), _mm256_mul_ps(nc.z, np.z));
        const __m256 dd = _mm256_mul_ps(d, d), lim = _mm256_mul_ps(cs2, _mm256_mul_ps(ncl, npl));
        const __m256 dpos = _mm256_cmp_ps(d, zero, _CMP_GE_OQ);
        const __m256 cos_ok = cs_pos ? _mm256_and_ps(dpos, _mm256_cmp_ps(dd, lim, _CMP_GE_OQ))
                                     : _mm256_or_ps(dpos, _mm256_cmp_ps(dd, lim, _CMP_LE_OQ));
        const __m256 agree = _mm256_or_ps(_mm256_and_ps(cbg, pbg), _mm256_andnot_ps(_mm256_or_ps(cbg, pbg), cos_ok));
        ok = _mm256_and_ps(ok, agree);
        mask = _mm256_or_si256(mask, _mm256_and_si256(_mm256_castps_si256(ok), _mm256_set1_epi32(1 << k)));
      }
    }
    // Bytes out: values < 16 pack without saturation.
    const __m256i both = _mm256_packus_epi32(in, mask);  // per 128-bit half: in0-3 mask0-3 | in4-7 mask4-7
    const __m256i bytes = _mm256_packus_epi16(both, both);
    const std::uint64_t lo = std::uint64_t(_mm256_extract_epi64(bytes, 0)), hi = std::uint64_t(_mm256_extract_epi64(bytes, 2));
    const std::uint64_t ins = (lo & 0xffffffffu) | (hi << 32), msk = (lo >> 32) | (hi & 0xffffffff00000000ull);
    __builtin_memcpy(a.inside + x, &ins, 8);
    __builtin_memcpy(a.taps + x, &msk, 8);
    const int kept = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(mask, _mm256_setzero_si256())));
    lost += std::size_t(8 - __builtin_popcount(unsigned(kept)));
  }
  return lost;
}

}  // namespace mcr::detail

#else

namespace mcr::detail {
bool tap_row_avx2_available() { return false; }
std::size_t tap_row_avx2(const TapRow&, int, int) { return 0; }
}  // namespace mcr::detail

#endif
