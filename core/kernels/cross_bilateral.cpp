#include "kernels/cross_bilateral.h"

// The kernel's W-lane vectors only live inside always-inlined code of functions
// compiled for the matching instruction set; GCC warns that returning them would
// change the ABI elsewhere, which never happens.
#pragma GCC diagnostic ignored "-Wpsabi"

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "kernels/cross_bilateral_block.h"
#include "kernels/cross_bilateral_symmetric.h"
#include "kernels/fast_exp.h"
#include "kernels/feature_guides.h"
#include "util/error.h"
#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

namespace {

using namespace cross_kernel;  // the block and the symmetric path, simd's vectors

// Rows y0, y0 + ystep, ... < y1 (box coordinates) of the region's columns [x0, x1),
// W pixels at a time. The symmetric path is given the rows of one residue
// (ystep = the tap step) and recomputes the ring rows above y0 it needs.
template <int W, bool C, int N3>
MCR_INLINE void cross_rows_impl(const CrossPass& a, int y0, int y1, int ystep, int x0, int x1) {
  const GuidePlanes<N3> gp(a);
  const Flags fl{gp.ggd != nullptr, a.s != nullptr || a.s_const != 0.0f, a.radius != nullptr};
  if constexpr (W >= 8) {  // the generic build keeps the plain path (compile time; any CPU of ours has AVX2)
    if (symmetric(a) && a.off.size() == 5) return symmetric_rows<W, C, N3, 5>(a, gp, fl, y0, y1, x0, x1);
    if (symmetric(a) && a.off.size() == 3) return symmetric_rows<W, C, N3, 3>(a, gp, fl, y0, y1, x0, x1);
  }
  for (int y = y0; y < y1; y += ystep)
    for (int x = x0; x < x1; x += W) cross_block<W, C, N3>(a, gp, fl, y, x, std::min(W, x1 - x));
}

using RowFn = void (*)(const CrossPass&, int, int, int, int, int);
constexpr int kBandRows = 32;  // rows per task; the symmetric path recomputes 2 ring rows per band

template <bool C, int N3>
void row_generic(const CrossPass& a, int y0, int y1, int ys, int x0, int x1) {
  cross_rows_impl<4, C, N3>(a, y0, y1, ys, x0, x1);
}

#ifdef MCR_X86_DISPATCH
// Same source; the attributes let GCC use the wider registers and contract a*b+c to FMA.
template <bool C, int N3>
__attribute__((target("avx2,fma"), optimize("fp-contract=fast"), flatten)) void row_avx2(const CrossPass& a, int y0,
                                                                                         int y1, int ys, int x0,
                                                                                         int x1) {
  cross_rows_impl<8, C, N3>(a, y0, y1, ys, x0, x1);
}
template <bool C, int N3>
__attribute__((target("avx512f,fma"), optimize("fp-contract=fast"), flatten)) void row_avx512(const CrossPass& a,
                                                                                             int y0, int y1, int ys,
                                                                                             int x0, int x1) {
  cross_rows_impl<16, C, N3>(a, y0, y1, ys, x0, x1);
}
#endif

// Index: bit 2 colour weight, bits 0-1 number of three-channel guides.
template <template <bool, int> class Row, std::size_t... I>
constexpr std::array<RowFn, sizeof...(I)> make_table(std::index_sequence<I...>) {
  return {Row<bool((I >> 2) & 1), int(I & 3)>::fn...};
}
template <bool C, int N3>
struct Generic {
  static constexpr RowFn fn = &row_generic<C, N3>;
};
#ifdef MCR_X86_DISPATCH
template <bool C, int N3>
struct Avx2 {
  static constexpr RowFn fn = &row_avx2<C, N3>;
};
template <bool C, int N3>
struct Avx512 {
  static constexpr RowFn fn = &row_avx512<C, N3>;
};
#endif

RowFn pick_row_fn(bool c, int n3) {
  const std::size_t index = (std::size_t(c) << 2) | std::size_t(n3);
  static const auto generic = make_table<Generic>(std::make_index_sequence<8>{});
#ifdef MCR_X86_DISPATCH
  static const auto avx2 = make_table<Avx2>(std::make_index_sequence<8>{});
  static const auto avx512 = make_table<Avx512>(std::make_index_sequence<8>{});
  switch (isa()) {
    case Isa::Avx512: return avx512[index];
    case Isa::Avx2: return avx2[index];
    case Isa::Generic: break;
  }
#endif
  return generic[index];
}

}  // namespace

void cross_filter(const CrossPass& a, const Roi& region, int nthreads) {
  if (region.empty()) return;
  int n3 = 0;
  bool depth = false;
  for (const Guides::Guide* g : a.guides) {
    if (g->channels == 3) ++n3;
    else if (depth) throw Error(Errc::Internal, "cross_filter: more than one one-channel guide");
    else depth = true;
  }
  if (n3 > 3) throw Error(Errc::Internal, "cross_filter: more than three three-channel guides");
  if (a.off.empty() || a.off.size() != a.h.size()) throw Error(Errc::Internal, "cross_filter: bad tap grid");
  const RowFn fn = pick_row_fn(a.colour_weight, n3);
  const Roi& box = a.pb.box;
  if (region.x0 < box.x0 || region.y0 < box.y0 || region.x1 > box.x1 || region.y1 > box.y1)
    throw Error(Errc::Internal, "cross_filter: region outside the planes");
  const int bx = region.x0 - box.x0, ex = region.x1 - box.x0, by = region.y0 - box.y0, ey = region.y1 - box.y0;
  // Tasks: bands of rows, or, for the symmetric path, bands of the rows of one
  // residue mod the tap step (the result does not depend on the bands).
  const int ystep = symmetric(a) && isa() != Isa::Generic ? a.off[1] - a.off[0] : 1;
  std::vector<std::pair<int, int>> bands;  // first row, end
  for (int r = 0; r < ystep; ++r) {
    const int first = by + ((r - by) % ystep + ystep) % ystep;
    const int rows = first < ey ? (ey - first + ystep - 1) / ystep : 0;
    for (int k = 0; k < rows; k += kBandRows)
      bands.emplace_back(first + k * ystep, std::min(ey, first + (k + kBandRows) * ystep));
  }
  parallel_rows(0, int(bands.size()), nthreads,
                [&](int i) { fn(a, bands[std::size_t(i)].first, bands[std::size_t(i)].second, ystep, bx, ex); });
}

float fast_exp_neg(float e) { return exp_neg_v<8>(splat<8>(e))[0]; }

}  // namespace mcr
