#pragma once
// Catmull-Rom lookup of BMFR's planar RGB TAA history (bmfr_taa.cpp and its AVX2 loops).
#include <algorithm>
#include <cstddef>

#include "temporal/reprojection.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mcr {

inline void cr_weights(float t, float* wt) {
  const float t2 = t * t, t3 = t2 * t;
  wt[0] = 0.5f * (-t3 + 2 * t2 - t);
  wt[1] = 0.5f * (3 * t3 - 5 * t2 + 2);
  wt[2] = 0.5f * (-3 * t3 + 4 * t2 + t);
  wt[3] = 0.5f * (t3 - t2);
}

// Catmull-Rom sample of the planar RGB history at (x, y) (pixel centres at integers),
// taps clamped to the border. False when (x, y) lies outside the image.
inline bool catmull_rom_planar(const float* hist, int w, int h, std::size_t n, float x, float y, float* out) {
  if (!(x >= -0.5f && y >= -0.5f && x <= float(w) - 0.5f && y <= float(h) - 0.5f)) return false;
  const int ix = floor_int(x), iy = floor_int(y);
  float wx[4], wy[4];
  cr_weights(x - float(ix), wx);
  cr_weights(y - float(iy), wy);
  const int bx = ix - 1, by = iy - 1;
  if (bx >= 0 && by >= 0 && bx + 3 < w && by + 3 < h) {  // interior: no clamping
    const float* base = hist + std::size_t(by) * std::size_t(w) + std::size_t(bx);
#if defined(__SSE2__)
    // Per channel: the 4 tap rows weighted by wy (lanes = tap columns), then the dot
    // with wx; the three dots are finished together by a 4x4 transpose.
    const __m128 wy0 = _mm_set1_ps(wy[0]), wy1 = _mm_set1_ps(wy[1]), wy2 = _mm_set1_ps(wy[2]), wy3 = _mm_set1_ps(wy[3]);
    const __m128 wxv = _mm_loadu_ps(wx);
    __m128 acc[3];
    for (int c = 0; c < 3; ++c) {
      const float* p = base + std::size_t(c) * n;
      __m128 a = _mm_mul_ps(wy0, _mm_loadu_ps(p));
      a = _mm_add_ps(a, _mm_mul_ps(wy1, _mm_loadu_ps(p + w)));
      a = _mm_add_ps(a, _mm_mul_ps(wy2, _mm_loadu_ps(p + 2 * std::size_t(w))));
      a = _mm_add_ps(a, _mm_mul_ps(wy3, _mm_loadu_ps(p + 3 * std::size_t(w))));
      acc[c] = _mm_mul_ps(a, wxv);
    }
    __m128 r0 = acc[0], r1 = acc[1], r2 = acc[2], r3 = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    const __m128 s = _mm_add_ps(_mm_add_ps(r0, r1), _mm_add_ps(r2, r3));
    float o4[4];
    _mm_storeu_ps(o4, s);
    out[0] = o4[0];
    out[1] = o4[1];
    out[2] = o4[2];
#else
    for (int c = 0; c < 3; ++c) {
      const float* p = base + std::size_t(c) * n;
      float col[4] = {0, 0, 0, 0};
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) col[i] += wy[j] * p[std::size_t(j) * std::size_t(w) + std::size_t(i)];
      out[c] = (col[0] * wx[0] + col[1] * wx[1]) + (col[2] * wx[2] + col[3] * wx[3]);
    }
#endif
    return true;
  }
  int xs[4], ys[4];
  for (int i = 0; i < 4; ++i) {
    xs[i] = std::clamp(bx + i, 0, w - 1);
    ys[i] = std::clamp(by + i, 0, h - 1);
  }
  for (int c = 0; c < 3; ++c) {
    const float* p = hist + std::size_t(c) * n;
    float acc = 0;
    for (int j = 0; j < 4; ++j) {
      const float* row = p + std::size_t(ys[j]) * std::size_t(w);
      float r = 0;
      for (int i = 0; i < 4; ++i) r += wx[i] * row[xs[i]];
      acc += wy[j] * r;
    }
    out[c] = acc;
  }
  return true;
}

}  // namespace mcr
