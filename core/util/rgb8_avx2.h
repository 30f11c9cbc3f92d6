#pragma once
// Interleaved RGB <-> three planes, 8 pixels at a time, with AVX2 shuffles (for code
// built with __attribute__((target("avx2"))) on x86-64 GCC; no gathers: on the EPYC
// hosts a gather costs more than these 9 shuffles).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#include <immintrin.h>

namespace mcr {

// p[0..23] = r0 g0 b0 r1 g1 b1 ... -> r, g, b (lane l = pixel l).
__attribute__((target("avx2"), always_inline)) inline void load_rgb8(const float* p, __m256& r, __m256& g, __m256& b) {
  // Pixels 0-3 in the low 128-bit halves, 4-7 in the high ones.
  const __m256 m03 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p)), _mm_loadu_ps(p + 12), 1);
  const __m256 m14 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 4)), _mm_loadu_ps(p + 16), 1);
  const __m256 m25 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 8)), _mm_loadu_ps(p + 20), 1);
  const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));
  const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));
  r = _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0));
  g = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
  b = _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1));
}

// The inverse: r, g, b -> p[0..23] interleaved.
__attribute__((target("avx2"), always_inline)) inline void store_rgb8(float* p, __m256 r, __m256 g, __m256 b) {
  const __m256 rg = _mm256_shuffle_ps(r, g, _MM_SHUFFLE(2, 0, 2, 0));
  const __m256 gb = _mm256_shuffle_ps(g, b, _MM_SHUFFLE(3, 1, 3, 1));
  const __m256 br = _mm256_shuffle_ps(b, r, _MM_SHUFFLE(3, 1, 2, 0));
  const __m256 m03 = _mm256_shuffle_ps(rg, br, _MM_SHUFFLE(2, 0, 2, 0));
  const __m256 m14 = _mm256_shuffle_ps(gb, rg, _MM_SHUFFLE(3, 1, 2, 0));
  const __m256 m25 = _mm256_shuffle_ps(br, gb, _MM_SHUFFLE(3, 1, 3, 1));
  _mm_storeu_ps(p, _mm256_castps256_ps128(m03));
  _mm_storeu_ps(p + 4, _mm256_castps256_ps128(m14));
  _mm_storeu_ps(p + 8, _mm256_castps256_ps128(m25));
  _mm_storeu_ps(p + 12, _mm256_extractf128_ps(m03, 1));
  _mm_storeu_ps(p + 16, _mm256_extractf128_ps(m14, 1));
  _mm_storeu_ps(p + 20, _mm256_extractf128_ps(m25, 1));
}

}  // namespace mcr
#endif
