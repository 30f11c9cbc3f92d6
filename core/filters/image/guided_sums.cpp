#include "filters/image/guided_sums.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "util/parallel.h"

namespace mcr::guided {

namespace {

// Running box sums with exact restarts. Rows are stored in blocks of kLanes pixels,
// channel by channel inside a block (block b, channel q, lane t at
// [(b * C + q) * kLanes + t]): the per-pixel work runs on GCC vectors of kLanes
// doubles (SSE2 on any x86-64, AVX when built for it), and the horizontal running
// sums read one pixel's channels at fixed offsets.
//
// Stage 1 sums, per pixel, the stacked values
//   [n | z_j | z_j z_l (l <= j) | p_c | z_j p_c | (outliers: n_o | p_c | z_j p_c)]
// where n counts the valid pixels and z is the normalised guide; stage 2 sums the
// coefficients of each window
//   [n | a_cj | b_c | mean p_c] (+ the same again for windows holding an outlier).
// Counts are small integers, exact in double, so "count == 0" is exact, and every
// channel it covers is reset to exactly 0 there (a multiplication by 0 or 1).
#if defined(__AVX__)
typedef double Lanes __attribute__((vector_size(32)));
#else
typedef double Lanes __attribute__((vector_size(16)));
#endif
constexpr int kLanes = int(sizeof(Lanes) / sizeof(double));

inline Lanes vload(const double* p) {
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void vstore(double* p, const Lanes& v) { std::memcpy(p, &v, sizeof v); }
inline std::size_t blocks(std::size_t n) { return (n + kLanes - 1) / kLanes; }

template <int D, bool OUT, bool MP>
struct Layout {
  // Pixel rows: what stage 1 reads of one image row, 0 where the pixel is left out.
  static constexpr int PV = 0, PZ = 1, PS = 1 + D, PB = 4 + D, PO = 7 + D;
  static constexpr int NP = OUT ? 8 + D : 4 + D;
  // Stage 1 sums.
  static constexpr int NZZ = D * (D + 1) / 2;
  static constexpr int IZ = 1, IZZ = 1 + D, IP = IZZ + NZZ, IZP = IP + 3, CS = IZP + 3 * D;
  static constexpr int IBN = CS, IBP = CS + 1, IBZP = CS + 4;
  static constexpr int C1 = OUT ? CS + 4 + 3 * D : CS;
  // Stage 2 sums (a second tier at +C2S for windows holding an outlier); the mean
  // colours only when some output pixel has no finite guide (MP).
  static constexpr int JA = 1, JB = 1 + 3 * D, JM = JB + 3, C2S = MP ? JM + 3 : JM;
  static constexpr int C2 = OUT ? 2 * C2S : C2S;
  // Guide rows for the output: z_j, then 1 where the guide is finite.
  static constexpr int NG = D + 1;
};

// Channel q of pixel x (0-based) in a blocked row of C channels.
template <int C>
inline std::size_t at(std::size_t x, int q) {
  return (x / kLanes * C + std::size_t(q)) * kLanes + x % kLanes;
}

// The pixel row of image row y, columns [x0, x1), blocked; padding lanes are 0.
template <int D, bool OUT, bool MP>
void load_row(const Ctx& c, int y, int x0, int x1, double* __restrict P) {
  using L = Layout<D, OUT, MP>;
  const GuideView<D> gv(c);
  const std::uint8_t* flags = c.flags;
  const float* colour = c.colour;
  const double threshold = c.threshold;
  const std::size_t n = std::size_t(x1 - x0), nb = blocks(n);
  for (std::size_t x = 0; x < nb * kLanes; ++x) {
    if (x >= n) {
      for (int q = 0; q < L::NP; ++q) P[at<L::NP>(x, q)] = 0.0;
      continue;
    }
    const std::size_t i = std::size_t(y) * std::size_t(c.w) + std::size_t(x0) + x;
    const std::uint8_t f = flags[i];
    if ((f & kStat) != kStat) {
      for (int q = 0; q < L::NP; ++q) P[at<L::NP>(x, q)] = 0.0;
      continue;
    }
    P[at<L::NP>(x, L::PV)] = 1.0;
    for (int j = 0; j < D; ++j) P[at<L::NP>(x, L::PZ + j)] = gv.z(i, j);
    const float* p = colour + i * 3;
    const bool big = OUT && std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])}) >= threshold;
    for (int k = 0; k < 3; ++k) {
      P[at<L::NP>(x, L::PS + k)] = big ? 0.0 : double(p[k]);
      if (OUT) P[at<L::NP>(x, L::PB + k)] = big ? double(p[k]) : 0.0;
    }
    if (OUT) P[at<L::NP>(x, L::PO)] = big ? 1.0 : 0.0;
  }
}

// The guide of image row y, columns [x0, x1), for the output (blocked, NG channels).
template <int D>
void load_guide(const Ctx& c, int y, int x0, int x1, double* __restrict G) {
  constexpr int NG = D + 1;
  const GuideView<D> gv(c);
  const std::uint8_t* flags = c.flags;
  const std::size_t n = std::size_t(x1 - x0), nb = blocks(n);
  for (std::size_t x = 0; x < nb * kLanes; ++x) {
    const std::size_t i = std::size_t(y) * std::size_t(c.w) + std::size_t(x0) + x;
    const bool ok = x < n && (flags[i] & kGuideOk);
    for (int j = 0; j < D; ++j) G[at<NG>(x, j)] = ok ? gv.z(i, j) : 0.0;
    G[at<NG>(x, D)] = ok ? 1.0 : 0.0;
  }
}

// V += stack(pixel row I) - stack(pixel row O), nb blocks; then the exact restarts.
template <int D, bool OUT, bool MP>
void vertical_step(double* __restrict V, const double* __restrict I, const double* __restrict O, std::size_t nb) {
  using L = Layout<D, OUT, MP>;
  constexpr int K = kLanes;
  const Lanes zero = Lanes{} * 0.0, one = zero + 1.0;
  for (std::size_t b = 0; b < nb; ++b) {
    double* v = V + b * L::C1 * K;
    const double* pi = I + b * L::NP * K;
    const double* po = O + b * L::NP * K;
    auto upd = [&](int q, const Lanes& add, const Lanes& sub, const Lanes& keep) {
      vstore(v + q * K, ((vload(v + q * K) + add) - sub) * keep);
    };
    const Lanes cnt = (vload(v) + vload(pi + L::PV * K)) - vload(po + L::PV * K);
    const Lanes keep = cnt != zero ? one : zero;
    vstore(v, cnt);
    Lanes zi[D], zo[D];
    for (int j = 0; j < D; ++j) {
      zi[j] = vload(pi + (L::PZ + j) * K);
      zo[j] = vload(po + (L::PZ + j) * K);
      upd(L::IZ + j, zi[j], zo[j], keep);
    }
    int m = L::IZZ;
    for (int j = 0; j < D; ++j)
      for (int l = 0; l <= j; ++l) upd(m++, zi[j] * zi[l], zo[j] * zo[l], keep);
    for (int k = 0; k < 3; ++k) {
      const Lanes a = vload(pi + (L::PS + k) * K), s = vload(po + (L::PS + k) * K);
      upd(L::IP + k, a, s, keep);
      for (int j = 0; j < D; ++j) upd(L::IZP + k * D + j, zi[j] * a, zo[j] * s, keep);
    }
    if (OUT) {
      const Lanes cb = ((vload(v + L::IBN * K) + vload(pi + L::PO * K)) - vload(po + L::PO * K)) * keep;
      const Lanes keepb = cb != zero ? one : zero;
      vstore(v + L::IBN * K, cb);
      for (int k = 0; k < 3; ++k) {
        const Lanes a = vload(pi + (L::PB + k) * K), s = vload(po + (L::PB + k) * K);
        upd(L::IBP + k, a, s, keepb);
        for (int j = 0; j < D; ++j) upd(L::IBZP + k * D + j, zi[j] * a, zo[j] * s, keepb);
      }
    }
  }
}

// Stage 1 restarts on one window's sums (s[0] = valid count, s[IBN] = outlier count).
template <int D, bool OUT, bool MP>
inline void settle1(double* s) {
  using L = Layout<D, OUT, MP>;
  if (s[0] == 0.0) {
    std::fill(s, s + L::C1, 0.0);
  } else if (OUT && s[L::IBN] == 0.0) {
    std::fill(s + L::IBN, s + L::C1, 0.0);
  }
}

template <int D, bool OUT, bool MP>
inline void settle2(double* s) {
  using L = Layout<D, OUT, MP>;
  if (s[0] == 0.0) std::fill(s, s + L::C2S, 0.0);
  if (OUT && s[L::C2S] == 0.0) std::fill(s + L::C2S, s + L::C2, 0.0);
}

// Horizontal running sums over blocked rows of C channels: out pixel x - o0 gets
// the sum of in pixels k - i0 for k in [x - r, x + r] clipped to [i0, i1), for x in
// [o0, o1); the padding lanes of out are set to 0.
template <int C, class Settle>
void horizontal(const double* __restrict in, int i0, int i1, double* __restrict out, int o0, int o1, int r,
                Settle settle) {
  constexpr int K = kLanes;
  auto pix = [&](int k) { return in + at<C>(std::size_t(k - i0), 0); };
  double s[C];
  std::fill(s, s + C, 0.0);
  for (int k = std::max(i0, o0 - r); k < std::min(i1, o0 + r + 1); ++k) {
    const double* a = pix(k);
    for (int q = 0; q < C; ++q) s[q] += a[q * K];
  }
  settle(s);
  for (int x = o0; x < o1; ++x) {
    if (x > o0) {
      const int ki = x + r, ko = x - r - 1;
      const bool add = ki < i1, sub = ko >= i0;
      if (add && sub) {
        const double *a = pix(ki), *b = pix(ko);
        for (int q = 0; q < C; ++q) s[q] = (s[q] + a[q * K]) - b[q * K];
      } else if (add) {
        const double* a = pix(ki);
        for (int q = 0; q < C; ++q) s[q] += a[q * K];
      } else if (sub) {
        const double* b = pix(ko);
        for (int q = 0; q < C; ++q) s[q] -= b[q * K];
      }
      settle(s);
    }
    double* o = out + at<C>(std::size_t(x - o0), 0);
    for (int q = 0; q < C; ++q) o[q * K] = s[q];
  }
  for (std::size_t x = std::size_t(o1 - o0); x < blocks(std::size_t(o1 - o0)) * K; ++x)
    for (int q = 0; q < C; ++q) out[at<C>(x, q)] = 0.0;
}

// Window sums -> coefficients, kLanes windows at a time (an LDL^T solve per lane).
template <int D, bool OUT, bool MP>
void solve_row(const double* __restrict S, double* __restrict A, std::size_t nb, double eps_) {
  using L = Layout<D, OUT, MP>;
  constexpr int K = kLanes;
  const Lanes zero = Lanes{} * 0.0, one = zero + 1.0, eps = zero + eps_;
  for (std::size_t bk = 0; bk < nb; ++bk) {
    const double* s = S + bk * L::C1 * K;
    double* a = A + bk * L::C2 * K;
    auto ld = [&](int q) { return vload(s + q * K); };
    const Lanes cnt = ld(0);
    const Lanes inv = one / (cnt > zero ? cnt : one);
    Lanes mu[D], M[D][D], dg[D], dinv[D], mp[3], rhs[3][D];
    for (int j = 0; j < D; ++j) mu[j] = ld(L::IZ + j) * inv;
    int m = L::IZZ;
    for (int j = 0; j < D; ++j)
      for (int l = 0; l <= j; ++l, ++m) M[j][l] = ld(m) * inv - mu[j] * mu[l];
    for (int j = 0; j < D; ++j) M[j][j] = (M[j][j] > zero ? M[j][j] : zero) + eps;
    for (int k = 0; k < 3; ++k) {
      Lanes ps = ld(L::IP + k);
      if (OUT) ps += ld(L::IBP + k);
      mp[k] = ps * inv;
      for (int j = 0; j < D; ++j) {
        Lanes q = ld(L::IZP + k * D + j);
        if (OUT) q += ld(L::IBZP + k * D + j);
        rhs[k][j] = q * inv - mu[j] * mp[k];
      }
    }
    // LDL^T of Sigma + eps I. Every pivot of that matrix is >= eps in exact
    // arithmetic, so flooring them at eps only catches rounding (and NaN).
    for (int j = 0; j < D; ++j) {
      for (int l = 0; l < j; ++l) {
        Lanes v = M[j][l];
        for (int q = 0; q < l; ++q) v -= M[j][q] * M[l][q] * dg[q];
        M[j][l] = v * dinv[l];
      }
      Lanes dj = M[j][j];
      for (int q = 0; q < j; ++q) dj -= M[j][q] * M[j][q] * dg[q];
      dg[j] = dj > eps ? dj : eps;
      dinv[j] = one / dg[j];
    }
    const Lanes okf = cnt > zero ? one : zero;
    const Lanes big = OUT ? (ld(L::IBN) > zero ? one : zero) : zero;
    const Lanes small = okf - big;
    auto put = [&](int q, const Lanes& v) {
      vstore(a + q * K, v * small);
      if (OUT) vstore(a + (L::C2S + q) * K, v * big);
    };
    put(0, one);
    for (int k = 0; k < 3; ++k) {
      Lanes y[D];
      for (int j = 0; j < D; ++j) {
        Lanes v = rhs[k][j];
        for (int l = 0; l < j; ++l) v -= M[j][l] * y[l];
        y[j] = v;
      }
      for (int j = 0; j < D; ++j) y[j] *= dinv[j];
      for (int j = D - 1; j >= 0; --j) {
        Lanes v = y[j];
        for (int l = j + 1; l < D; ++l) v -= M[l][j] * y[l];
        y[j] = v;
      }
      Lanes bb = mp[k];
      for (int j = 0; j < D; ++j) {
        put(L::JA + k * D + j, y[j]);
        bb -= y[j] * mu[j];
      }
      put(L::JB + k, bb);
      if (MP) put(L::JM + k, mp[k]);
    }
  }
}

// V2 += ring row I - ring row O (either may be null), nb blocks; then the restarts.
template <int D, bool OUT, bool MP>
void vertical_step2(double* __restrict V, const double* I, const double* O, std::size_t nb) {
  using L = Layout<D, OUT, MP>;
  constexpr int K = kLanes;
  const Lanes zero = Lanes{} * 0.0, one = zero + 1.0;
  for (std::size_t b = 0; b < nb; ++b) {
    double* v = V + b * L::C2 * K;
    const std::size_t off = b * L::C2 * K;
    auto upd = [&](int q) {
      Lanes s = vload(v + q * K);
      if (I) s += vload(I + off + q * K);
      if (O) s -= vload(O + off + q * K);
      return s;
    };
    const Lanes cnt = upd(0);
    const Lanes keep = cnt != zero ? one : zero;
    vstore(v, cnt);
    for (int q = 1; q < L::C2S; ++q) vstore(v + q * K, upd(q) * keep);
    if (OUT) {
      const Lanes cb = upd(L::C2S);
      const Lanes keepb = cb != zero ? one : zero;
      vstore(v + L::C2S * K, cb);
      for (int q = L::C2S + 1; q < L::C2; ++q) vstore(v + q * K, upd(q) * keepb);
    }
  }
}

// Coefficient sums -> output colour Q (blocked, 4 channels: RGB, window count).
template <int D, bool OUT, bool MP>
void output_row(const double* __restrict V, const double* __restrict G, double* __restrict Q, std::size_t nb) {
  using L = Layout<D, OUT, MP>;
  constexpr int K = kLanes, NG = L::NG;
  const Lanes zero = Lanes{} * 0.0, one = zero + 1.0;
  for (std::size_t b = 0; b < nb; ++b) {
    const double* v = V + b * L::C2 * K;
    const double* g = G + b * NG * K;
    auto ld = [&](int q) { return OUT ? vload(v + q * K) + vload(v + (L::C2S + q) * K) : vload(v + q * K); };
    const Lanes cnt = ld(0);
    const Lanes inv = one / (cnt > zero ? cnt : one);
    const Lanes gok = vload(g + D * K);
    Lanes z[D];
    for (int j = 0; j < D; ++j) z[j] = vload(g + j * K);
    double* o = Q + b * 4 * K;
    for (int k = 0; k < 3; ++k) {
      Lanes q = ld(L::JB + k);
      for (int j = 0; j < D; ++j) q += ld(L::JA + k * D + j) * z[j];
      // No guide value here: each window's model at its own mean guide, i.e. the
      // window's mean colour.
      vstore(o + k * K, (MP ? (gok > zero ? q : ld(L::JM + k)) : q) * inv);
    }
    vstore(o + 3 * K, cnt);
  }
}

template <int D, bool OUT, bool MP>
void run_bands_as(const Ctx& c, const Roi& roi, Image& out, int nthreads, int band_h,
                  std::vector<std::vector<double>>& work) {
  using L = Layout<D, OUT, MP>;
  constexpr int C1 = L::C1, C2 = L::C2, K = kLanes;
  const int r = c.r, W = c.w, H = c.h;
  // Window centres the roi needs, and the pixels those windows cover (columns).
  const int kx0 = std::max(0, roi.x0 - r), kx1 = std::min(W, roi.x1 + r);
  const int ix0 = std::max(0, kx0 - r), ix1 = std::min(W, kx1 + r);
  const int ox0 = roi.x0, ox1 = roi.x1;
  const std::size_t BK = blocks(std::size_t(kx1 - kx0)), BI = blocks(std::size_t(ix1 - ix0)),
                    BO = blocks(std::size_t(ox1 - ox0));
  // Bands lie on the image's grid of band_h rows, whatever the roi: a sliding sum's rounding
  // depends on where it started, so a roi (a tiled run's band of the frame) computes its
  // first band from the grid line above it (rows before the roi are summed, not written).
  const int ys = roi.y0 - roi.y0 % band_h;
  const int nb = (roi.y1 - ys + band_h - 1) / band_h;
  if (work.size() < std::size_t(nb)) work.resize(std::size_t(nb));

  parallel_rows(0, nb, nthreads, [&](int band) {
    const int ya = ys + band * band_h, yb = std::min(roi.y1, ya + band_h);
    const int k0 = std::max(0, ya - r), k1 = std::min(H, yb + r);  // coefficient rows
    const std::size_t R = std::size_t(std::min(2 * r + 2, k1 - k0));  // ring of their row sums
    // One allocation per band, kept by the filter between calls (no page faults
    // on the next frame).
    const std::size_t row2 = BO * C2 * K;
    const std::size_t sizes[] = {BI * C1 * K, BK * C1 * K, BK * C2 * K, R * row2, row2,
                                 BI * L::NP * K, BI * L::NP * K, BI * L::NP * K, BO * L::NG * K, BO * 4 * K};
    constexpr int kBuffers = int(sizeof sizes / sizeof sizes[0]);
    std::size_t total = 0;
    for (std::size_t s : sizes) total += s;
    std::vector<double>& mem = work[std::size_t(band)];
    if (mem.size() < total) mem.resize(total);
    double* ptrs[kBuffers];
    {
      double* p = mem.data();
      for (int q = 0; q < kBuffers; ++q) {
        ptrs[q] = p;
        p += sizes[q];
      }
    }
    double *V = ptrs[0], *S = ptrs[1], *A = ptrs[2], *ring = ptrs[3], *V2 = ptrs[4], *Pin = ptrs[5],
           *Pout = ptrs[6], *zero = ptrs[7], *G = ptrs[8], *Q = ptrs[9];
    std::fill(V, V + sizes[0], 0.0);
    std::fill(zero, zero + sizes[7], 0.0);
    auto ring_row = [&](int k) { return ring + (std::size_t(k) % R) * row2; };

    auto add_rows = [&](int yi, int yo) {
      const double* I = zero;
      const double* O = zero;
      if (yi >= 0) {
        load_row<D, OUT, MP>(c, yi, ix0, ix1, Pin);
        I = Pin;
      }
      if (yo >= 0) {
        load_row<D, OUT, MP>(c, yo, ix0, ix1, Pout);
        O = Pout;
      }
      vertical_step<D, OUT, MP>(V, I, O, BI);
    };

    // Coefficient row k -> the horizontal sums of its coefficients, into the ring.
    auto coefficient_row = [&](int k) {
      if (k == k0) {
        for (int y = std::max(0, k0 - r); y < std::min(H, k0 + r + 1); ++y) add_rows(y, -1);
      } else {
        add_rows(k + r < H ? k + r : -1, k - r - 1 >= 0 ? k - r - 1 : -1);
      }
      horizontal<C1>(V, ix0, ix1, S, kx0, kx1, r, [](double* s) { settle1<D, OUT, MP>(s); });
      solve_row<D, OUT, MP>(S, A, BK, c.eps);
      horizontal<C2>(A, kx0, kx1, ring_row(k), ox0, ox1, r, [](double* s) { settle2<D, OUT, MP>(s); });
    };

    auto emit = [&](int y) {
      if (y == ya) {
        std::fill(V2, V2 + row2, 0.0);
        for (int k = std::max(0, y - r); k < std::min(H, y + r + 1); ++k)
          vertical_step2<D, OUT, MP>(V2, ring_row(k), nullptr, BO);
      } else {
        const int ki = y + r, ko = y - r - 1;
        vertical_step2<D, OUT, MP>(V2, ki < H ? ring_row(ki) : nullptr, ko >= 0 ? ring_row(ko) : nullptr, BO);
      }
      if (y < roi.y0) return;
      load_guide<D>(c, y, ox0, ox1, G);
      output_row<D, OUT, MP>(V2, G, Q, BO);
      float* o = out.pixel(ox0, y);
      for (std::size_t x = 0; x < std::size_t(ox1 - ox0); ++x, o += 3) {
        const double* q = Q + at<4>(x, 0);
        if (!(q[3 * K] > 0.0)) {  // no window with a valid pixel: keep the input where finite
          for (int k = 0; k < 3; ++k) o[k] = std::isfinite(o[k]) ? o[k] : 0.0f;
        } else {
          for (int k = 0; k < 3; ++k) {
            const double v = q[k * K];
            o[k] = v == v ? float(std::clamp(v, -double(FLT_MAX), double(FLT_MAX))) : 0.0f;
          }
        }
      }
    };

    int ny = ya;
    for (int k = k0; k < k1; ++k) {
      coefficient_row(k);
      while (ny < yb && std::min(H - 1, ny + r) <= k) emit(ny++);
    }
  });
}

}  // namespace

template <int D>
void run_bands(const Ctx& c, bool outliers, bool mean_colours, const Roi& roi, Image& out, int nthreads, int band_h,
               std::vector<std::vector<double>>& work) {
  if (outliers && mean_colours)
    run_bands_as<D, true, true>(c, roi, out, nthreads, band_h, work);
  else if (outliers)
    run_bands_as<D, true, false>(c, roi, out, nthreads, band_h, work);
  else if (mean_colours)
    run_bands_as<D, false, true>(c, roi, out, nthreads, band_h, work);
  else
    run_bands_as<D, false, false>(c, roi, out, nthreads, band_h, work);
}

// The guide sizes of GuidedFilter::run().
template void run_bands<1>(const Ctx&, bool, bool, const Roi&, Image&, int, int, std::vector<std::vector<double>>&);
template void run_bands<3>(const Ctx&, bool, bool, const Roi&, Image&, int, int, std::vector<std::vector<double>>&);
template void run_bands<4>(const Ctx&, bool, bool, const Roi&, Image&, int, int, std::vector<std::vector<double>>&);
template void run_bands<6>(const Ctx&, bool, bool, const Roi&, Image&, int, int, std::vector<std::vector<double>>&);
template void run_bands<7>(const Ctx&, bool, bool, const Roi&, Image&, int, int, std::vector<std::vector<double>>&);

}  // namespace mcr::guided
