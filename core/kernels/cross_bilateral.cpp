#include "kernels/cross_bilateral.h"

// The kernel's W-lane vectors only live inside always-inlined code of functions
// compiled for the matching instruction set; GCC warns that returning them would
// change the ABI elsewhere, which never happens.
#pragma GCC diagnostic ignored "-Wpsabi"

#include <algorithm>
#include <array>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <utility>

#include "kernels/fast_exp.h"
#include "kernels/feature_guides.h"
#include "kernels/planes.h"
#include "util/error.h"
#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

// ---------------------------------------------------------------------------
// The kernel: W pixels of a row at once, every tap of the grid in turn, the
// centre's values and the sums in registers. Written once over GCC vector
// extensions and compiled for three instruction sets.

namespace {

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
bool even_taps(const CrossPass& a) {
  const std::size_t n = a.off.size();
  if (n < 2) return false;
  const int step = a.off[1] - a.off[0];
  if (step <= 0) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (a.off[i] != (int(i) - int(n / 2)) * step || a.h[i] != a.h[n - 1 - i]) return false;
  return true;
}

bool symmetric(const CrossPass& a) {
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
