#pragma once
// The kernels' exponential, written here: exp_neg_v, the W-lane float exp(-e) of the
// edge-avoiding kernels and of pwaf's windows (GCC vector extensions; cross_bilateral.cpp
// with its block and symmetric headers, feature_regression.cpp and pwaf_window.cpp, only
// inside always-inlined code of functions compiled for one instruction set).
#include <cstdint>
#include <cstring>

#ifndef MCR_INLINE
#define MCR_INLINE inline __attribute__((always_inline))
#endif

namespace mcr {
namespace simd {

template <int W>
struct Vec {
  typedef float f __attribute__((vector_size(4 * W)));
  typedef std::int32_t i __attribute__((vector_size(4 * W)));
};

template <int W>
MCR_INLINE typename Vec<W>::f splat(float v) {
  typename Vec<W>::f r = {};
  return r + v;
}

// exp(-e) for e >= 0: exact 1 at 0, 0 for e >= 86 and for NaN / +inf, else
// within 2e-7 relative: e^x = 2^n e^r with n = round(x / ln2), r = x - n ln2
// (ln2 split in two so that r is exact: Cody & Waite), e^r by Taylor to r^6.
template <int W>
MCR_INLINE typename Vec<W>::f exp_neg_v(typename Vec<W>::f e) {
  using vf = typename Vec<W>::f;
  using vi = typename Vec<W>::i;
  const vi ok = e < splat<W>(86.0f);
  const vf x = ok ? -e : splat<W>(0.0f);
  const vf n = (x * 1.44269504f + 12582912.0f) - 12582912.0f;  // round(x log2 e) (1.5 * 2^23 trick)
  const vf r = (x - n * 0.693359375f) - n * -2.12194440e-4f;   // ln2 = 0.693359375 - 2.12194440e-4
  vf p = r * (1.0f / 720.0f) + (1.0f / 120.0f);               // |r| <= 0.347: Taylor error < 1.3e-7
  p = p * r + (1.0f / 24.0f);
  p = p * r + (1.0f / 6.0f);
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  const vi bits = (__builtin_convertvector(n, vi) + 127) << 23;  // 2^n, n >= -125 here
  vf scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return ok ? p * scale : splat<W>(0.0f);
}

}  // namespace simd
}  // namespace mcr
