#pragma once
// The symmetric path of the cross-bilateral kernel (kernels/cross_bilateral.h), which
// computes each pair of taps' exponential once, over the block of
// cross_bilateral_block.h; only cross_bilateral.cpp includes it, whose row builds
// instantiate it per instruction set.
#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <vector>

#include "kernels/cross_bilateral.h"
#include "kernels/cross_bilateral_block.h"
#include "kernels/fast_exp.h"
#include "kernels/feature_guides.h"
#include "kernels/planes.h"

namespace mcr::cross_kernel {

// Symmetric taps. When nothing of the weight depends on the centre alone (no
// per-pixel colour a, k, s or window), the exponent of tap d at p equals that of
// tap -d at p + d bit for bit ((c_p - c_q) a and (c_q - c_p) a differ in sign
// only), so each pair's exponential is computed once: every pixel computes the
// taps after the centre in kernel order into a ring of rows, and the taps before
// the centre read them back at p + d. The sums still run in kernel order, so the
// result is the one of cross_block, bit for bit. A centre with an unusable colour
// leaves the colour out of its exponents (not symmetric): its block takes every
// tap directly.
//
// Taps spaced `step` rows apart (a-trous pass 2^(i-1)) only link rows of the same
// residue y mod step, so the rows are taken one residue at a time (y, y + step,
// ...): the ring then holds n/2 + 1 rows whatever the step, and the 5 input rows a
// row reads stay in cache from one row to the next.
constexpr int kMaxSymmetricTaps = 5;  // 1D; k_g = 9 would need a ring of 40 planes
// The ring must stay in the L2 cache with the input rows.
constexpr std::size_t kMaxRingBytes = 512 * 1024;

// Ring layout for W lanes: `rows` rows of c planes of `plane` floats, `pad` each
// side; row y of the pass lives in slot (y / step) % rows.
struct Ring {
  int rows, pad, step;
  std::size_t plane;
  std::ptrdiff_t stride;  // one row of all planes
  Ring(const CrossPass& a, int w) {
    const int n = int(a.off.size()), reach = a.off.back();
    step = n > 1 ? a.off[1] - a.off[0] : 1;
    rows = n / 2 + 1;
    pad = reach + w;
    plane = std::size_t(a.pb.box.width() + 2 * pad);
    stride = std::ptrdiff_t(plane) * ((n * n - 1) / 2);
  }
  std::size_t floats() const { return std::size_t(stride) * std::size_t(rows); }
  float* row(float* ring, int y) const { return ring + std::ptrdiff_t(y / step % rows) * stride + pad; }
};

// Evenly spaced symmetric offsets (the ring's row slots rely on it).
inline bool even_taps(const CrossPass& a) {
  const std::size_t n = a.off.size();
  if (n < 2) return false;
  const int step = a.off[1] - a.off[0];
  if (step <= 0) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (a.off[i] != (int(i) - int(n / 2)) * step || a.h[i] != a.h[n - 1 - i]) return false;
  return true;
}

inline bool symmetric(const CrossPass& a) {
  if (a.off.size() > std::size_t(kMaxSymmetricTaps) || a.colour_a || a.s || a.s_const != 0.0f || a.radius ||
      !even_taps(a))
    return false;
  if (Ring(a, 16).floats() * sizeof(float) > kMaxRingBytes) return false;
  for (const Guides::Guide* g : a.guides)
    if (!g->k.empty()) return false;
  return true;
}

// A W-lane vector at any float address; it aliases float only (a memcpy store
// would alias everything and make GCC reload every plane pointer after it).
template <int W>
struct UVec {
  typedef float f __attribute__((vector_size(4 * W), aligned(4)));
};

// What the symmetric path reads of a pass, copied out of it: plain locals stay
// in registers across the ring stores. The colour's a is the constant one (a
// centre with an unusable colour has a = 0 in cross_block; its ring values only
// ever meet valid = 0, so they may take a).
template <int N3>
struct SymPlanes {
  const float* c[3];
  const float* g[3 * (N3 > 0 ? N3 : 1)];
  const float* d;
  float kg[N3 > 0 ? N3 : 1], kd, ac;
  SymPlanes(const CrossPass& a, const GuidePlanes<N3>& gp) {
    for (int k = 0; k < 3; ++k) c[k] = a.colour[k];
    for (int k = 0; k < 3 * N3; ++k) g[k] = gp.g3[k];
    for (int j = 0; j < N3; ++j) kg[j] = gp.gg3[j]->k_const;
    d = gp.gd;
    kd = gp.ggd ? gp.ggd->k_const : 0.0f;
    const float v = a.colour_a_const * a.colour_amul;  // as load_centre: a * amul, at most 1e18
    ac = v < 1e18f ? v : 1e18f;
  }
};

// exp(-e) h of the taps after the centre for the columns [x0, x1) of row y, into
// its ring row (plane k of tap c + 1 + k); h is the tap weight, so that the sums
// take w = ring * valid, which is ex * (valid * h) bit for bit as valid is 0 or 1.
// Taps with every lane outside the image store 0 without loading (the pixels
// that read them are outside too). The exponent is exponent()'s without its
// spatial term (symmetric() asks for none): the same bits.
template <int W, bool C, int N3, bool D, int N>
MCR_INLINE void symmetric_half(const SymPlanes<N3> sp, const float* hh, int step, int bw, int bh, std::size_t stride,
                               int y, int x0, int x1, float* slot, std::size_t plane) {
  using vf = typename Vec<W>::f;
  using uvf = typename UVec<W>::f;
  constexpr int c = (N * N - 1) / 2;
  const std::size_t crow = std::size_t(y) * stride + kPlanePad;
  int rows = N / 2 + 1;  // rows y, y + step, ... inside the box
  while (rows > 1 && y + (rows - 1) * step >= bh) --rows;
  const vf ac = splat<W>(sp.ac);
  vf kg[N3 > 0 ? N3 : 1];
  for (int j = 0; j < N3; ++j) kg[j] = splat<W>(sp.kg[j]);
  const vf kd = splat<W>(sp.kd);
  for (int x = x0; x < x1; x += W) {
    vf pc[3], pg[N3 > 0 ? N3 : 1][3], pd = splat<W>(0.0f);
    for (int k = 0; k < 3; ++k) pc[k] = load_full<W>(sp.c[k] + crow, x);
    for (int j = 0; j < N3; ++j)
      for (int k = 0; k < 3; ++k) pg[j][k] = load_full<W>(sp.g[3 * j + k] + crow, x);
    if constexpr (D) pd = load_full<W>(sp.d + crow, x);
    const bool inner = x - (N / 2) * step + W > 0 && x + (N / 2) * step < bw;  // no tap wholly outside
#pragma GCC unroll 4
    for (int j = N / 2; j < N; ++j) {
      if (j - N / 2 >= rows) break;
      const std::size_t qrow = std::size_t(y + (j - N / 2) * step) * stride + kPlanePad;
#pragma GCC unroll 8
      for (int i = j == N / 2 ? N / 2 + 1 : 0; i < N; ++i) {
        const int t = j * N + i, qx = x + (i - N / 2) * step;
        vf ex = splat<W>(0.0f);
        if (inner || (qx + W > 0 && qx < bw)) {
          const std::size_t q = qrow + std::size_t(std::ptrdiff_t(qx));
          vf e = splat<W>(0.0f);
          if constexpr (C) {
            const vf du = (pc[0] - load_full<W>(sp.c[0] + q, 0)) * ac;
            const vf dv = (pc[1] - load_full<W>(sp.c[1] + q, 0)) * ac;
            const vf dw = (pc[2] - load_full<W>(sp.c[2] + q, 0)) * ac;
            e = du * du + dv * dv + dw * dw;
          }
          for (int g = 0; g < N3; ++g) {
            const vf du = pg[g][0] - load_full<W>(sp.g[3 * g + 0] + q, 0);
            const vf dv = pg[g][1] - load_full<W>(sp.g[3 * g + 1] + q, 0);
            const vf dw = pg[g][2] - load_full<W>(sp.g[3 * g + 2] + q, 0);
            e = kg[g] * (du * du + dv * dv + dw * dw) + e;
          }
          if constexpr (D) {
            const vf du = pd - load_full<W>(sp.d + q, 0);
            e = kd * (du * du) + e;
          }
          ex = exp_neg_v<W>(e) * (hh[i] * hh[j]);
        }
        *reinterpret_cast<uvf*>(slot + std::size_t(t - c - 1) * plane + x) = ex;
      }
    }
  }
}

// Row y of the region's columns [x0, x1) from the ring.
template <int W, bool C, int N3, int N>
MCR_INLINE void symmetric_row(const CrossPass& a, const GuidePlanes<N3>& gp, Flags fl, int y, int x0, int x1,
                              const Ring& r, float* ring) {
  using vf = typename Vec<W>::f;
  constexpr int c = (N * N - 1) / 2;
  const int bw = a.pb.box.width(), bh = a.pb.box.height(), step = a.off[1] - a.off[0];
  const std::size_t crow = std::size_t(y) * std::size_t(a.pb.stride) + kPlanePad;
  float hh[N];
  for (int i = 0; i < N; ++i) hh[i] = a.h[std::size_t(i)];
  const float* after = r.row(ring, y);  // taps after the centre: at p
  const float* before[N];               // taps before the centre: at q, row j
  std::size_t qrow[N];
  bool in[N];
  for (int j = 0; j < N; ++j) {
    const int qy = y + (j - N / 2) * step;
    in[j] = qy >= 0 && qy < bh;
    qrow[j] = in[j] ? std::size_t(qy) * std::size_t(a.pb.stride) + kPlanePad : 0;
    before[j] = in[j] ? r.row(ring, qy) : nullptr;
  }
  const float* ok = a.colour_ok + crow;
  int bad = 0;  // a centre with an unusable colour in the row (rare): blocks are checked one by one
  for (int x = x0; x < x1; ++x) bad |= !(ok[x] > 0.0f);
  const float* valid = a.valid;
  const float* col[3] = {a.colour[0], a.colour[1], a.colour[2]};
  // The sums of B blocks at x, x + W, ... at once: each sum is a chain of N^2
  // dependent FMAs, so interleaving independent blocks hides their latency.
  const auto sums = [&](auto blocks, int x, bool inner, Acc<W>* acc) {
    constexpr int B = decltype(blocks)::value;
    for (int b = 0; b < B; ++b) acc[b] = Acc<W>{splat<W>(0.0f), splat<W>(0.0f), splat<W>(0.0f), splat<W>(0.0f)};
#pragma GCC unroll 8
    for (int j = 0; j < N; ++j) {  // kernel order, the taps cross_block takes
      if (!in[j]) continue;
#pragma GCC unroll 8
      for (int i = 0; i < N; ++i) {
        const int t = j * N + i, qx = x + (i - N / 2) * step;
        if (!inner && (qx + W <= 0 || qx >= bw)) continue;
        for (int b = 0; b < B; ++b) {
          vf ex;
          if (t > c) ex = load_full<W>(after + std::size_t(t - c - 1) * r.plane, x + b * W);
          else if (t < c) ex = load_full<W>(before[j] + std::size_t(c - 1 - t) * r.plane, qx + b * W);
          else ex = splat<W>(1.0f * (hh[i] * hh[j]));  // the centre: e = 0 exactly
          const std::size_t q = qrow[j];
          const vf w = ex * load_full<W>(valid + q, qx + b * W);
          acc[b].c0 = w * load_full<W>(col[0] + q, qx + b * W) + acc[b].c0;
          acc[b].c1 = w * load_full<W>(col[1] + q, qx + b * W) + acc[b].c1;
          acc[b].c2 = w * load_full<W>(col[2] + q, qx + b * W) + acc[b].c2;
          acc[b].w = acc[b].w + w;
        }
      }
    }
  };
  const auto store = [&](const Acc<W>& acc, int x, int lanes) {
    vf cc[3];
    for (int k = 0; k < 3; ++k) cc[k] = load_full<W>(col[k] + crow, x);
    store_block<W>(a, acc, cc, load_full<W>(ok, x), crow + std::size_t(x), lanes);
  };
  const auto usable = [&](int x, int lanes) {
    bool u = true;
    for (int l = 0; l < lanes; ++l) u = u && ok[x + l] > 0.0f;
    return u;
  };
  for (int x = x0; x < x1;) {
    const int lanes = std::min(W, x1 - x);
    if (x + 2 * W <= x1 && x - (N / 2) * step + W > 0 && x + W + (N / 2) * step < bw &&
        (!bad || (usable(x, W) && usable(x + W, W)))) {
      Acc<W> acc[2];
      sums(std::integral_constant<int, 2>{}, x, true, acc);
      store(acc[0], x, W);
      store(acc[1], x + W, W);
      x += 2 * W;
      continue;
    }
    if (bad && !usable(x, lanes)) {
      cross_block<W, C, N3>(a, gp, fl, y, x, lanes);
    } else {
      Acc<W> acc[1];
      sums(std::integral_constant<int, 1>{}, x, x - (N / 2) * step + W > 0 && x + (N / 2) * step < bw, acc);
      store(acc[0], x, lanes);
    }
    x += W;
  }
}

template <int W, bool C, int N3, int N>
MCR_INLINE void symmetric_rows(const CrossPass& a, const GuidePlanes<N3>& gp, Flags fl, int y0, int y1, int x0,
                               int x1) {
  // One plane per tap after the centre, each row padded so that the reads of
  // lanes past the image stay inside (they get weight 0: every value in the ring
  // is finite, whatever call left it there).
  const Ring r(a, W);
  thread_local std::vector<float> ring;
  if (ring.size() < r.floats()) ring.assign(r.floats(), 0.0f);
  const int reach = a.off.back(), bw = a.pb.box.width();
  const int wx0 = std::max(0, x0 - reach), wx1 = std::min(bw, x1 + reach);  // columns the taps before the centre read
  int ys = y0;  // the rows above y0 whose taps after the centre reach it
  while (ys - r.step >= 0 && y0 - (ys - r.step) <= reach) ys -= r.step;
  const SymPlanes<N3> sp(a, gp);
  float hh[N];
  for (int i = 0; i < N; ++i) hh[i] = a.h[std::size_t(i)];
  const std::size_t stride = std::size_t(a.pb.stride);
  const int bh = a.pb.box.height();
  for (int y = ys; y < y1; y += r.step) {
    if (fl.depth)
      symmetric_half<W, C, N3, true, N>(sp, hh, r.step, bw, bh, stride, y, wx0, wx1, r.row(ring.data(), y), r.plane);
    else
      symmetric_half<W, C, N3, false, N>(sp, hh, r.step, bw, bh, stride, y, wx0, wx1, r.row(ring.data(), y), r.plane);
    if (y >= y0) symmetric_row<W, C, N3, N>(a, gp, fl, y, x0, x1, r, ring.data());
  }
}

}  // namespace mcr::cross_kernel
