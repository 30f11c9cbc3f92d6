#include "prepare/demodulation.h"

#include <cstddef>

#include "util/isa.h"
#include "util/parallel.h"

#ifdef MCR_X86_DISPATCH
#include <immintrin.h>
#endif

namespace mcr {

namespace {

#ifdef MCR_X86_DISPATCH
// n interleaved floats of an RGB albedo, 8 at a time (the scalar rule's operations);
// returns the first not done.
MCR_TARGET_AVX2 std::size_t demodulate_avx2(const float* ad, const float* co, float lo, float hi, std::size_t n,
                                            float* al, float* il) {
  const __m256 lo8 = _mm256_set1_ps(lo), hi8 = _mm256_set1_ps(hi), one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
  const __m256 tiny = _mm256_set1_ps(0x1p-126f), abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  std::size_t j = 0;
  for (; j + 8 <= n; j += 8) {
    const __m256 v = _mm256_loadu_ps(ad + j), c = _mm256_loadu_ps(co + j);
    const __m256 fin = _mm256_cmp_ps(_mm256_sub_ps(v, v), zero, _CMP_EQ_OQ);
    // std::min(std::max(v, lo), hi) = min_ps(hi, max_ps(lo, v)) (the second operand on equality, as std::).
    const __m256 a0 = _mm256_blendv_ps(one, _mm256_min_ps(hi8, _mm256_max_ps(lo8, v)), fin);
    // need = |c| 2^-126 where c is finite, else 0; std::max(a0, need) = max_ps(need, a0).
    const __m256 cfin = _mm256_cmp_ps(_mm256_sub_ps(c, c), zero, _CMP_EQ_OQ);
    const __m256 need = _mm256_and_ps(cfin, _mm256_mul_ps(_mm256_and_ps(c, abs_mask), tiny));
    const __m256 a = _mm256_max_ps(need, a0);
    _mm256_storeu_ps(al + j, a);
    _mm256_storeu_ps(il + j, _mm256_div_ps(c, a));
  }
  return j;
}
#endif

}  // namespace

void demodulate_row(const float* ad, int ach, const float* co, int n, float lo, float* al, float* il, float hi) {
  if (ach == 3) {  // the usual RGB albedo: one flat loop
    const std::size_t m = std::size_t(n) * 3;
    std::size_t j = 0;
#ifdef MCR_X86_DISPATCH
    if (isa_at_least(Isa::Avx2)) j = demodulate_avx2(ad, co, lo, hi, m, al, il);
#endif
    for (; j < m; ++j) {
      const float a = demodulation_divisor(ad[j], co[j], lo, hi);
      al[j] = a;
      il[j] = co[j] / a;
    }
    return;
  }
  for (std::size_t i = 0; i < std::size_t(n); ++i)
    for (int c = 0; c < 3; ++c) {
      const float a = demodulation_divisor(ad[i * std::size_t(ach) + std::size_t(std::min(c, ach - 1))],
                                           co[i * 3 + std::size_t(c)], lo, hi);
      al[i * 3 + std::size_t(c)] = a;
      il[i * 3 + std::size_t(c)] = co[i * 3 + std::size_t(c)] / a;
    }
}

void demodulate(const Image& albedo, float floor, const Roi& roi, int nthreads, Image& divisor, Image& colour) {
  if (roi.empty()) return;
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    float* c = colour.pixel(roi.x0, y);
    demodulate_row(albedo.pixel(roi.x0, y), albedo.channels(), c, roi.width(), floor, divisor.pixel(roi.x0, y), c);
  });
}

}  // namespace mcr
