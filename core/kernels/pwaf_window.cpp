#include "kernels/pwaf_window.h"

// The W-lane vectors only live inside always-inlined code of functions compiled for one
// instruction set; GCC warns that returning them would change the ABI elsewhere, which
// never happens.
#pragma GCC diagnostic ignored "-Wpsabi"

#include <algorithm>
#include <cfloat>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "kernels/fast_exp.h"
#include "util/error.h"
#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

namespace {

using namespace simd;  // Vec, splat, exp_neg_v

template <int W>
MCR_INLINE typename Vec<W>::f ld(const float* p) {
  typename Vec<W>::f v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// Row y's pixels [x, x + lanes) (box coordinates); `e` holds the exponents of the first pass.
template <int W, int NF>
MCR_INLINE void window_block(const PwafWindowPass& a, int y, int x, int lanes, std::vector<float>& e) {
  using vf = typename Vec<W>::f;
  using vi = typename Vec<W>::i;
  const int bw = a.pb.box.width(), bh = a.pb.box.height(), R = a.max_radius;
  const std::size_t stride = std::size_t(a.pb.stride);
  const std::size_t crow = std::size_t(y) * stride + kPlanePad + std::size_t(x);
  const vf inf = splat<W>(__builtin_inff());

  vf ref[3], own[3], fp[NF > 0 ? NF : 1][3];
  for (int c = 0; c < 3; ++c) {
    ref[c] = ld<W>(a.ref[c] + crow);
    own[c] = ld<W>(a.colour[c] + crow);
  }
  for (int k = 0; k < NF; ++k)
    for (int c = 0; c < 3; ++c) fp[k][c] = ld<W>(a.feature[k][c] + crow);
  const vf av = ld<W>(a.a + crow);
  vf r = ld<W>(a.radius + crow);
  float rmax = 0.0f;
  for (int l = 0; l < lanes; ++l) rmax = std::max(rmax, r[l]);
  for (int l = lanes; l < W; ++l) r[l] = -1.0f;  // lanes past the region: no tap
  const int rb = std::min(R, int(rmax));

  // The taps every lane may use, in one order for both passes.
  auto taps = [&](auto&& f) {
    for (int dy = -rb; dy <= rb; ++dy) {
      const int qy = y + dy;
      if (qy < 0 || qy >= bh) continue;
      const float* sp_row = &a.spatial[std::size_t(std::abs(dy)) * std::size_t(R + 1)];
      for (int dx = -rb; dx <= rb; ++dx) {
        const int qx = x + dx;
        if (qx + W <= 0 || qx >= bw) continue;  // every lane outside the box (pads read 0, valid 0)
        f(std::size_t(qy) * stride + kPlanePad + std::size_t(std::ptrdiff_t(qx)), sp_row[std::abs(dx)],
          float(std::max(std::abs(dx), std::abs(dy))));
      }
    }
  };

  // Pass 1: exponents (+inf where a lane may not use the tap) and their minimum.
  std::size_t n = 0;
  vf emin = inf;
  taps([&](std::size_t q, float sp, float m) {
    vf ex = splat<W>(sp);
    const vf d0 = (ref[0] - ld<W>(a.colour[0] + q)) * av, d1 = (ref[1] - ld<W>(a.colour[1] + q)) * av,
             d2 = (ref[2] - ld<W>(a.colour[2] + q)) * av;
    ex = ex + (d0 * d0 + d1 * d1 + d2 * d2);
    for (int k = 0; k < NF; ++k) {
      const vf u = fp[k][0] - ld<W>(a.feature[k][0] + q), v = fp[k][1] - ld<W>(a.feature[k][1] + q),
               w = fp[k][2] - ld<W>(a.feature[k][2] + q);
      const vf t = (u * u + v * v + w * w) * a.k[k];
      // A non-finite value at either pixel is NaN here (t > 0 is false): the term is left out;
      // an equal pair adds 0 even when k * d^2 would be inf * 0.
      ex = t > 0.0f ? ex + t : ex;
    }
    ex = ex < splat<W>(FLT_MAX) ? ex : splat<W>(FLT_MAX);  // inf sums stay comparable (all equal: equal weights)
    const vi ok = (ld<W>(a.valid + q) > 0.0f) & (splat<W>(m) <= r);
    ex = ok ? ex : inf;
    emin = ex < emin ? ex : emin;
    std::memcpy(&e[n], &ex, sizeof ex);
    n += W;
  });

  // Pass 2: weights relative to the smallest exponent (exp_neg_v gives 0 for +inf and NaN:
  // a lane with no usable tap sums nothing), deviations from the pixel's own colour.
  vf s0 = splat<W>(0.0f), s1 = s0, s2 = s0, sw = s0;
  n = 0;
  taps([&](std::size_t q, float, float) {
    vf ex;
    std::memcpy(&ex, &e[n], sizeof ex);
    n += W;
    const vf wt = exp_neg_v<W>(ex - emin);
    s0 = s0 + wt * (ld<W>(a.colour[0] + q) - own[0]);
    s1 = s1 + wt * (ld<W>(a.colour[1] + q) - own[1]);
    s2 = s2 + wt * (ld<W>(a.colour[2] + q) - own[2]);
    sw = sw + wt;
  });

  const vi has = sw > 0.0f;
  const vf den = has ? sw : splat<W>(1.0f);
  const vf zero = splat<W>(0.0f);
  const vf o0 = has ? own[0] + s0 / den : zero, o1 = has ? own[1] + s1 / den : zero, o2 = has ? own[2] + s2 / den : zero;
  const vf ook = has ? splat<W>(1.0f) : zero;
  for (int l = 0; l < lanes; ++l) {
    a.out[0][crow + std::size_t(l)] = o0[l];
    a.out[1][crow + std::size_t(l)] = o1[l];
    a.out[2][crow + std::size_t(l)] = o2[l];
    if (a.out_ok) a.out_ok[crow + std::size_t(l)] = ook[l];
  }
}

template <int W, int NF>
MCR_INLINE void window_rows(const PwafWindowPass& a, int y0, int y1, int x0, int x1) {
  const int side = 2 * a.max_radius + 1;
  std::vector<float> e(std::size_t(side) * std::size_t(side) * W);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; x += W) window_block<W, NF>(a, y, x, std::min(W, x1 - x), e);
}

using RowFn = void (*)(const PwafWindowPass&, int, int, int, int);

template <int NF>
void rows_generic(const PwafWindowPass& a, int y0, int y1, int x0, int x1) {
  window_rows<4, NF>(a, y0, y1, x0, x1);
}
#ifdef MCR_X86_DISPATCH
// Same source, wider registers; no contraction (the generic build's bits). No AVX-512
// build: with AVX-512F alone GCC's 16-lane selects made the kernel 4x slower than AVX2's
// (sunlit, 16 spp: 57 against 13 ms), and wider blocks waste more taps of small windows.
template <int NF>
__attribute__((target("avx2"), flatten)) void rows_avx2(const PwafWindowPass& a, int y0, int y1, int x0, int x1) {
  window_rows<8, NF>(a, y0, y1, x0, x1);
}
#endif

// The build for the instruction set in use and `nf` (0 to 3) features.
RowFn pick(int nf) {
  static constexpr RowFn generic[] = {rows_generic<0>, rows_generic<1>, rows_generic<2>, rows_generic<3>};
#ifdef MCR_X86_DISPATCH
  static constexpr RowFn avx2[] = {rows_avx2<0>, rows_avx2<1>, rows_avx2<2>, rows_avx2<3>};
  if (isa_at_least(Isa::Avx2)) return avx2[nf];
#endif
  return generic[nf];
}

constexpr int kBandRows = 8;

}  // namespace

void pwaf_window_filter(const PwafWindowPass& a, const Roi& region, int nthreads) {
  if (region.empty()) return;
  if (a.features < 0 || a.features > 3) throw Error(Errc::Internal, "pwaf_window_filter: 0 to 3 features");
  if (a.spatial.size() != std::size_t(a.max_radius + 1) * std::size_t(a.max_radius + 1))
    throw Error(Errc::Internal, "pwaf_window_filter: spatial table size");
  const Roi& box = a.pb.box;
  if (region.x0 < box.x0 || region.y0 < box.y0 || region.x1 > box.x1 || region.y1 > box.y1)
    throw Error(Errc::Internal, "pwaf_window_filter: region outside the planes");
  const RowFn fn = pick(a.features);
  const int bx = region.x0 - box.x0, ex = region.x1 - box.x0, by = region.y0 - box.y0, ey = region.y1 - box.y0;
  const int bands = (ey - by + kBandRows - 1) / kBandRows;
  parallel_rows(0, bands, nthreads, [&](int i) {
    const int y0 = by + i * kBandRows;
    fn(a, y0, std::min(ey, y0 + kBandRows), bx, ex);
  });
}

}  // namespace mcr
