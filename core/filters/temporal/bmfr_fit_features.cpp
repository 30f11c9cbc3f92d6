#include "filters/temporal/bmfr_fit_features.h"

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include "kernels/feature_activity.h"
#include "util/avx2_shuffles.h"

namespace mcr::bmfr {

FeatureLayout layout_of(const std::string& set) {
  FeatureLayout l;
  if (set == "first_order") l.squares = false;
  if (set == "with_albedo") l.albedo = true;
  if (set == "with_depth") l.depth = true;
  return l;
}

unsigned constant_columns(const FeatureLayout& lay, const Image& nrm, const Image& pos, const Image* alb,
                          const Image* dep, int nthreads, std::vector<std::string>& notes) {
  struct Src {
    const Image* im;
    const char* name;
    int raw0, channels, columns;  // channels tested, raw columns they feed
  };
  const int albedo_columns = lay.albedo ? 3 : lay.albedo_luminance ? 1 : 0;
  const Src srcs[4] = {{&nrm, "normal", 0, 3, 3},
                       {&pos, "position", 3, 3, 3},
                       {albedo_columns ? alb : nullptr, lay.albedo ? "albedo" : "albedo (its luminance)", 6, 3,
                        albedo_columns},
                       {dep, "depth", 6 + albedo_columns, 1, 1}};
  unsigned drop = 0;
  for (const Src& s : srcs) {
    if (!s.im) continue;
    const Roi all = Roi::all(s.im->width(), s.im->height());
    const FeatureActivity a =
        feature_activity(*s.im, std::min(s.channels, s.im->channels()), all, Tolerance(0.0, 0.49e-5), nthreads);
    if (a.kind != Activity::Constant) continue;
    for (int c = 0; c < s.columns; ++c) drop |= 1u << lay.column_of_raw(s.raw0 + c);
    if (s.raw0 == 3 && lay.squares) drop |= 7u << 7;  // the squares of a constant position
    notes.push_back(activity_note(s.name, a, all, all.width(), all.height(), "left out of the regression"));
  }
  return drop;
}

void masked_min_max(const float* src, const float* mask, int np, float& lo, float& hi) {
  int i = 0;
  float l = INFINITY, u = -INFINITY;
#if defined(__SSE2__)
  const __m128 inf = _mm_set1_ps(INFINITY), ninf = _mm_set1_ps(-INFINITY), zero = _mm_setzero_ps();
  __m128 l4 = inf, u4 = ninf, l4b = inf, u4b = ninf;
  for (; i + 8 <= np; i += 8) {
    const __m128 m = _mm_cmpneq_ps(_mm_loadu_ps(mask + i), zero), mb = _mm_cmpneq_ps(_mm_loadu_ps(mask + i + 4), zero);
    const __m128 v = _mm_loadu_ps(src + i), vb = _mm_loadu_ps(src + i + 4);
    l4 = _mm_min_ps(l4, _mm_or_ps(_mm_and_ps(m, v), _mm_andnot_ps(m, inf)));
    u4 = _mm_max_ps(u4, _mm_or_ps(_mm_and_ps(m, v), _mm_andnot_ps(m, ninf)));
    l4b = _mm_min_ps(l4b, _mm_or_ps(_mm_and_ps(mb, vb), _mm_andnot_ps(mb, inf)));
    u4b = _mm_max_ps(u4b, _mm_or_ps(_mm_and_ps(mb, vb), _mm_andnot_ps(mb, ninf)));
  }
  float lt[4], ut[4];
  _mm_storeu_ps(lt, _mm_min_ps(l4, l4b));
  _mm_storeu_ps(ut, _mm_max_ps(u4, u4b));
  for (int k = 0; k < 4; ++k) {
    l = std::min(l, lt[k]);
    u = std::max(u, ut[k]);
  }
#endif
  for (; i < np; ++i)
    if (mask[i] != 0.0f) {
      l = std::min(l, src[i]);
      u = std::max(u, src[i]);
    }
  lo = l;
  hi = u;
}

void scale_masked(const float* src, const float* mask, int np, float lo, float sc, float* dst) {
  int i = 0;
#if defined(__SSE2__)
  const __m128 lo4 = _mm_set1_ps(lo), sc4 = _mm_set1_ps(sc), one = _mm_set1_ps(1.0f), mone = _mm_set1_ps(-1.0f),
               zero = _mm_setzero_ps();
  for (; i + 4 <= np; i += 4) {
    const __m128 m = _mm_cmpneq_ps(_mm_loadu_ps(mask + i), zero);
    const __m128 v = _mm_sub_ps(_mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(src + i), lo4), sc4), one);
    _mm_storeu_ps(dst + i, _mm_and_ps(m, _mm_min_ps(_mm_max_ps(v, mone), one)));
  }
#endif
  for (; i < np; ++i) {
    const float v = std::clamp((src[i] - lo) * sc - 1.0f, -1.0f, 1.0f);
    dst[i] = mask[i] != 0.0f ? v : 0.0f;
  }
}

#ifdef MCR_FIT_GATHER_AVX2
__attribute__((target("avx2"))) int gather_row_avx2(const float* nrow, const float* prow, const float* arow,
                                                     const float* irow, const float* vrow, int n8, int p,
                                                     std::size_t snp, float* raw, float* fin, float* zp, int* rows,
                                                     int W) {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 k0 = _mm256_set1_ps(0.2126f), k1 = _mm256_set1_ps(0.7152f), k2 = _mm256_set1_ps(0.0722f);
  const int nraw = arow ? 7 : 6;
  for (int x = 0; x < n8; x += 8, p += 8) {
    __m256 v[7], z[3];
    load_rgb8(nrow + std::size_t(x) * 3, v[0], v[1], v[2]);
    load_rgb8(prow + std::size_t(x) * 3, v[3], v[4], v[5]);
    load_rgb8(irow + std::size_t(x) * 3, z[0], z[1], z[2]);
    if (arow) {  // albedo_luminance(): (k0 r + k1 g) + k2 b, no FMA
      __m256 a[3];
      load_rgb8(arow + std::size_t(x) * 3, a[0], a[1], a[2]);
      v[6] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(k0, a[0]), _mm256_mul_ps(k1, a[1])), _mm256_mul_ps(k2, a[2]));
    }
    __m256 f = zero;  // 0 where all features are finite, NaN otherwise
    for (int c = 0; c < nraw; ++c) {
      _mm256_storeu_ps(raw + std::size_t(c) * snp + std::size_t(p), v[c]);
      f = _mm256_add_ps(f, _mm256_sub_ps(v[c], v[c]));
    }
    const __m256 ok = _mm256_cmp_ps(f, zero, _CMP_EQ_OQ);
    _mm256_storeu_ps(fin + p, _mm256_and_ps(ok, one));
    for (int c = 0; c < 3; ++c) _mm256_storeu_ps(zp + std::size_t(c) * snp + std::size_t(p), z[c]);
    const int fit = _mm256_movemask_ps(_mm256_and_ps(ok, _mm256_cmp_ps(_mm256_loadu_ps(vrow + x), zero, _CMP_GT_OQ)));
    for (int l = 0; l < 8; ++l) {
      rows[W] = p + l;
      W += (fit >> l) & 1;
    }
  }
  return W;
}
#endif

}  // namespace mcr::bmfr
