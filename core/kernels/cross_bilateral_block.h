#pragma once
// The block of the cross-bilateral kernel (kernels/cross_bilateral.h): W pixels of a
// row at once, every tap of the grid in turn, the centre's values and the sums in
// registers. Written once over GCC vector extensions and compiled for three
// instruction sets: only cross_bilateral.cpp includes it, whose row builds instantiate
// it per level; cross_bilateral_symmetric.h takes its loads, sums and stores.

// The W-lane vectors only live inside always-inlined code of functions compiled for the
// matching instruction set (see cross_bilateral.cpp).
#pragma GCC diagnostic ignored "-Wpsabi"

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>

#include "kernels/cross_bilateral.h"
#include "kernels/fast_exp.h"
#include "kernels/feature_guides.h"
#include "kernels/planes.h"

namespace mcr::cross_kernel {

using namespace simd;  // Vec, splat, exp_neg_v (kernels/fast_exp.h)

template <int W>
MCR_INLINE typename Vec<W>::f load_full(const float* row, int x) {
  typename Vec<W>::f v;
  std::memcpy(&v, row + x, sizeof v);
  return v;
}

// Per-pixel plane or constant.
template <int W>
MCR_INLINE typename Vec<W>::f load_or(const float* plane, float c, std::size_t row, int x) {
  return plane ? load_full<W>(plane + row, x) : splat<W>(c);
}

template <int W, int N3>
struct Centre {
  using vf = typename Vec<W>::f;
  vf c[3];                   // colour
  vf ac;                     // colour sqrt(k) (0 when the colour is unusable)
  vf g[N3 > 0 ? N3 : 1][3];  // three-channel guides
  vf kg[N3 > 0 ? N3 : 1];
  vf d, kd;                  // depth
  vf s, r;                   // spatial coefficient, window radius
  vf cok;                    // colour usable
};

template <int W>
struct Acc {
  typename Vec<W>::f c0, c1, c2, w;
};

struct Flags {
  bool depth, spatial, radius;
};

// The guide planes of one pass, sorted: three-channel ones, then depth.
template <int N3>
struct GuidePlanes {
  const float* g3[3 * (N3 > 0 ? N3 : 1)] = {};
  const Guides::Guide* gg3[N3 > 0 ? N3 : 1] = {};
  const Guides::Guide* ggd = nullptr;
  const float* gd = nullptr;
  explicit GuidePlanes(const CrossPass& a) {
    int j = 0;
    for (const Guides::Guide* g : a.guides) {
      if (g->channels == 3 && j < N3) {
        for (int c = 0; c < 3; ++c) g3[3 * j + c] = g->c[c].data();
        gg3[j++] = g;
      } else if (g->channels == 1) {
        ggd = g;
      }
    }
    gd = ggd ? ggd->c[0].data() : nullptr;
  }
};

template <int W, bool C, int N3>
MCR_INLINE void load_centre(const CrossPass& a, const GuidePlanes<N3>& gp, Flags fl, std::size_t crow, int x,
                            Centre<W, N3>& p) {
  constexpr float amax = 1e18f;
  for (int c = 0; c < 3; ++c) p.c[c] = load_full<W>(a.colour[c] + crow, x);
  p.cok = load_full<W>(a.colour_ok + crow, x);
  if constexpr (C) {
    // a stays finite (a * 0 = 0 for equal colours, never inf * 0).
    const typename Vec<W>::f ac = load_or<W>(a.colour_a, a.colour_a_const, crow, x) * a.colour_amul;
    p.ac = (ac < amax ? ac : splat<W>(amax)) * p.cok;
  } else {
    p.ac = splat<W>(0.0f);
  }
  for (int j = 0; j < N3; ++j) {
    for (int c = 0; c < 3; ++c) p.g[j][c] = load_full<W>(gp.g3[3 * j + c] + crow, x);
    p.kg[j] = load_or<W>(gp.gg3[j]->k.empty() ? nullptr : gp.gg3[j]->k.data(), gp.gg3[j]->k_const, crow, x);
  }
  if (gp.ggd) {
    p.d = load_full<W>(gp.gd + crow, x);
    p.kd = load_or<W>(gp.ggd->k.empty() ? nullptr : gp.ggd->k.data(), gp.ggd->k_const, crow, x);
  } else {
    p.d = p.kd = splat<W>(0.0f);
  }
  p.s = load_or<W>(a.s, a.s_const, crow, x);
  p.r = fl.radius ? load_full<W>(a.radius + crow, x) : splat<W>(0.0f);
}

// The exponent of tap (dx, dy) for a block of W pixels: qrow + qu addresses the
// first pixel's neighbour; the padded rows keep every load in bounds (lanes past
// the image read 0 with valid 0).
template <int W, bool C, int N3>
MCR_INLINE typename Vec<W>::f exponent(const CrossPass& a, const Centre<W, N3>& pu, const GuidePlanes<N3>& gp,
                                       Flags fl, std::size_t qrow, int qu, float d2) {
  using vf = typename Vec<W>::f;
  const auto ld = [](const float* row, int x) { return load_full<W>(row, x); };
  vf e = fl.spatial ? pu.s * d2 : splat<W>(0.0f);
  if constexpr (C) {
    const vf du = (pu.c[0] - ld(a.colour[0] + qrow, qu)) * pu.ac, dv = (pu.c[1] - ld(a.colour[1] + qrow, qu)) * pu.ac,
             dw = (pu.c[2] - ld(a.colour[2] + qrow, qu)) * pu.ac;
    e = du * du + dv * dv + dw * dw + e;
  }
  for (int j = 0; j < N3; ++j) {
    const vf du = pu.g[j][0] - ld(gp.g3[3 * j + 0] + qrow, qu);
    const vf dv = pu.g[j][1] - ld(gp.g3[3 * j + 1] + qrow, qu);
    const vf dw = pu.g[j][2] - ld(gp.g3[3 * j + 2] + qrow, qu);
    e = pu.kg[j] * (du * du + dv * dv + dw * dw) + e;
  }
  if (fl.depth) {
    const vf du = pu.d - ld(gp.gd + qrow, qu);
    e = pu.kd * (du * du) + e;
  }
  return e;
}

// Adds tap q (weight ex = exp(-e) before valid and h) to the block's sums.
template <int W>
MCR_INLINE void accumulate(const CrossPass& a, std::size_t qrow, int qu, typename Vec<W>::f ex, float h,
                           Acc<W>& acc) {
  using vf = typename Vec<W>::f;
  const vf w = ex * (load_full<W>(a.valid + qrow, qu) * h);
  acc.c0 = w * load_full<W>(a.colour[0] + qrow, qu) + acc.c0;
  acc.c1 = w * load_full<W>(a.colour[1] + qrow, qu) + acc.c1;
  acc.c2 = w * load_full<W>(a.colour[2] + qrow, qu) + acc.c2;
  acc.w = acc.w + w;
}

// Tap (dx, dy) for a block of W pixels.
template <int W, bool C, int N3>
MCR_INLINE void tap(const CrossPass& a, const Centre<W, N3>& pu, const GuidePlanes<N3>& gp, Flags fl,
                    std::size_t qrow, int qu, float h, float d2, float m, Acc<W>& acc) {
  using vf = typename Vec<W>::f;
  const auto ld = [](const float* row, int x) { return load_full<W>(row, x); };
  const vf q0 = ld(a.colour[0] + qrow, qu);
  const vf q1 = ld(a.colour[1] + qrow, qu);
  const vf q2 = ld(a.colour[2] + qrow, qu);
  const vf e = exponent<W, C, N3>(a, pu, gp, fl, qrow, qu, d2);
  vf w = exp_neg_v<W>(e) * (ld(a.valid + qrow, qu) * h);
  if (fl.radius) w = splat<W>(m) <= pu.r ? w : splat<W>(0.0f);
  acc.c0 = w * q0 + acc.c0;
  acc.c1 = w * q1 + acc.c1;
  acc.c2 = w * q2 + acc.c2;
  acc.w = acc.w + w;
}

// sum / weight of a block into the output planes at plane index i (its first
// `lanes` pixels); a pixel with no usable tap keeps its colour c (0 when unusable).
template <int W>
MCR_INLINE void store_block(const CrossPass& a, const Acc<W>& acc, const typename Vec<W>::f (&c)[3],
                            typename Vec<W>::f cok, std::size_t i, int lanes) {
  using vf = typename Vec<W>::f;
  using vi = typename Vec<W>::i;
  const vi has = acc.w > 0.0f;
  const vf wsafe = has ? acc.w : splat<W>(1.0f);
  const vf o0 = has ? acc.c0 / wsafe : c[0];
  const vf o1 = has ? acc.c1 / wsafe : c[1];
  const vf o2 = has ? acc.c2 / wsafe : c[2];
  const vf ook = (has | (cok > 0.0f)) ? splat<W>(1.0f) : splat<W>(0.0f);
  const vf ov = a.out_valid ? ook * load_full<W>(a.valid_mask + i, 0) : ook;
  if (lanes == W) {
    std::memcpy(a.out[0] + i, &o0, sizeof o0);
    std::memcpy(a.out[1] + i, &o1, sizeof o1);
    std::memcpy(a.out[2] + i, &o2, sizeof o2);
    if (a.out_ok) std::memcpy(a.out_ok + i, &ook, sizeof ook);
    if (a.out_valid) std::memcpy(a.out_valid + i, &ov, sizeof ov);
  } else {
    for (int l = 0; l < lanes; ++l) {
      a.out[0][i + l] = o0[l];
      a.out[1][i + l] = o1[l];
      a.out[2][i + l] = o2[l];
      if (a.out_ok) a.out_ok[i + l] = ook[l];
      if (a.out_valid) a.out_valid[i + l] = ov[l];
    }
  }
}

// The block of W pixels starting at x (box coordinates) of row y; `lanes` pixels
// of it belong to the region and are stored.
template <int W, bool C, int N3>
MCR_INLINE void cross_block(const CrossPass& a, const GuidePlanes<N3>& gp, Flags fl, int y, int x, int lanes) {
  const int bw = a.pb.box.width(), bh = a.pb.box.height();
  const int n = int(a.off.size());
  const std::size_t crow = std::size_t(y) * std::size_t(a.pb.stride) + kPlanePad;
  Centre<W, N3> p;
  load_centre<W, C, N3>(a, gp, fl, crow, x, p);
  int rb = 1 << 30;  // taps beyond every lane's window are skipped
  if (fl.radius) {
    float mr = 0.0f;
    for (int l = 0; l < lanes; ++l) mr = std::max(mr, p.r[l]);
    rb = int(mr);
  }

  Acc<W> acc{splat<W>(0.0f), splat<W>(0.0f), splat<W>(0.0f), splat<W>(0.0f)};
  for (int j = 0; j < n; ++j) {
    const int dy = a.off[j];
    if (std::abs(dy) > rb) continue;
    const int qy = y + dy;
    if (qy < 0 || qy >= bh) continue;
    const std::size_t qrow = std::size_t(qy) * std::size_t(a.pb.stride) + kPlanePad;
    const float hy = a.h[j];
    for (int i = 0; i < n; ++i) {
      const int dx = a.off[i];
      if (std::abs(dx) > rb) continue;
      const int qx = x + dx;
      if (qx + W <= 0 || qx >= bw) continue;  // every lane outside the image
      const float h = a.h[i] * hy;
      const float d2 = float(dx * dx + dy * dy);
      const float m = float(std::max(std::abs(dx), std::abs(dy)));
      tap<W, C, N3>(a, p, gp, fl, qrow, qx, h, d2, m, acc);
    }
  }

  store_block<W>(a, acc, p.c, p.cok, crow + std::size_t(x), lanes);
}

}  // namespace mcr::cross_kernel
