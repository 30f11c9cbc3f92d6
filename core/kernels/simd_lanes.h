#pragma once
// W-lane float vectors (simd::Vec<W>, GCC vector extensions) for a loop written once and
// built at several instruction-set levels (util/isa.h): loads and stores that also fill
// a row's last, partial vector, and min / max / clamp / abs / sqrt that give the bits of
// the SSE instructions and of the std:: forms they stand for, NaN included. Only for
// always-inlined code of functions compiled for one level.
#include <cmath>
#include <cstddef>
#include <cstring>

#include "kernels/fast_exp.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mcr {
namespace simd {

// A W-lane vector at any float address (it aliases float only).
template <int W>
struct Unaligned {
  typedef float f __attribute__((vector_size(4 * W), aligned(4)));
};

// Lanes [0, n) at p, n <= W (the rest 0): a row's tail reads nothing past the row.
template <int W>
MCR_INLINE typename Vec<W>::f load(const float* p, int n) {
  if (n == W) return *reinterpret_cast<const typename Unaligned<W>::f*>(p);
  typename Vec<W>::f v = {};
  std::memcpy(&v, p, sizeof(float) * std::size_t(n));
  return v;
}
template <int W>
MCR_INLINE void store(float* p, typename Vec<W>::f v, int n) {
  if (n == W)
    *reinterpret_cast<typename Unaligned<W>::f*>(p) = v;
  else
    std::memcpy(p, &v, sizeof(float) * std::size_t(n));
}

// Calls f(x, n) for the pixels [x, x + n) of a row of w: n = W but at the end.
template <int W, class F>
MCR_INLINE void for_lanes(int w, F&& f) {
  int x = 0;
  for (; x + W <= w; x += W) f(x, W);
  if (x < w) f(x, w - x);
}

// _mm_min_ps / _mm_max_ps: the second operand when either is NaN. So std::min(a, b),
// which is (b < a ? b : a), is vmin(b, a), and std::max(a, b) is vmax(b, a).
template <class V>
MCR_INLINE V vmin(V a, V b) {
  return a < b ? a : b;
}
template <class V>
MCR_INLINE V vmax(V a, V b) {
  return a > b ? a : b;
}
// std::clamp(v, lo, hi) = v < lo ? lo : (hi < v ? hi : v)
template <class V>
MCR_INLINE V vclamp(V v, V lo, V hi) {
  return v < lo ? lo : (hi < v ? hi : v);
}
template <int W>
MCR_INLINE typename Vec<W>::f vabs(typename Vec<W>::f v) {
  return typename Vec<W>::f(typename Vec<W>::i(v) & 0x7fffffff);
}

// Correctly rounded per lane, so any split gives the same bits: SSE2's sqrtps per 4
// lanes, an instruction generic code may inline (a 256-bit one it may not).
template <int W>
MCR_INLINE typename Vec<W>::f vsqrt(typename Vec<W>::f v) {
#if defined(__SSE2__)
  if constexpr (W == 4) {
    return typename Vec<4>::f(_mm_sqrt_ps(__m128(v)));
  } else {
    static_assert(W == 8, "4 or 8 lanes");
    const typename Vec<4>::f lo = vsqrt<4>(__builtin_shufflevector(v, v, 0, 1, 2, 3));
    const typename Vec<4>::f hi = vsqrt<4>(__builtin_shufflevector(v, v, 4, 5, 6, 7));
    return __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7);
  }
#else
  for (int k = 0; k < W; ++k) v[k] = std::sqrt(v[k]);
  return v;
#endif
}

}  // namespace simd
}  // namespace mcr
