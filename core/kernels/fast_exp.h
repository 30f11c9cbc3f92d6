#pragma once
// The kernels' exponentials, both written here: exp_neg_v, the W-lane float exp(-e) of the
// edge-avoiding kernels (GCC vector extensions; cross_bilateral.cpp with its block and
// symmetric headers, and feature_regression.cpp, only inside always-inlined code of
// functions compiled for one instruction set), and exp_neg_d, the double one of pwaf's
// weights (the float one's 2e-7 would show in pwaf's sums of up to 65^2 weights).
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
// exp(-d), d in [0, 40], double precision.
// exp(-d) for d in [0, 40]: 2^-(d log2 e) split into 2^n (exponent bits) times 2^f,
// |f| <= 1/2, with e^(f ln 2) by its Taylor series to degree 11 (relative error < 1e-14).
// Several times faster than std::exp and the same on every machine.
inline double exp_neg_d(double d) {
  const double t = -d * 1.4426950408889634;  // log2(e)
  const double n = -double(std::int64_t(0.5 - t));  // round half up, t <= 0
  const double x = (t - n) * 0.6931471805599453;  // ln 2, |x| <= 0.347
  double p = 1.0 / 39916800.0;
  p = p * x + 1.0 / 3628800.0;
  p = p * x + 1.0 / 362880.0;
  p = p * x + 1.0 / 40320.0;
  p = p * x + 1.0 / 5040.0;
  p = p * x + 1.0 / 720.0;
  p = p * x + 1.0 / 120.0;
  p = p * x + 1.0 / 24.0;
  p = p * x + 1.0 / 6.0;
  p = p * x + 0.5;
  p = p * x + 1.0;
  p = p * x + 1.0;
  const std::int64_t bits = (std::int64_t(n) + 1023) << 52;  // n in [-58, 0]: a normal double
  double scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

}  // namespace mcr
