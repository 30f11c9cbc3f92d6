#include "kernels/feature_regression.h"

// The kernel's L-lane vectors only live inside code inlined into functions compiled
// for one instruction set (see feature_weights.cpp).
#pragma GCC diagnostic ignored "-Wpsabi"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "kernels/fast_exp.h"
#include "kernels/feature_guides.h"
#include "kernels/planes.h"
#include "util/error.h"
#include "util/isa.h"
#include "util/parallel.h"

namespace mcr {

namespace {

// Solves A x = b for 3 right-hand sides by Cholesky (A symmetric, lower triangle
// used, overwritten). False when A is not numerically positive definite.
bool cholesky_solve(double* A, int n, double* b /* n x 3, row-major */) {
  for (int j = 0; j < n; ++j) {
    double d = A[j * n + j];
    for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
    if (!(d > 1e-12 * std::fabs(A[j * n + j])) || !(d > 0) || !std::isfinite(d)) return false;
    d = std::sqrt(d);
    A[j * n + j] = d;
    for (int i = j + 1; i < n; ++i) {
      double v = A[i * n + j];
      for (int k = 0; k < j; ++k) v -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = v / d;
    }
  }
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < n; ++i) {  // L y = b
      double v = b[i * 3 + c];
      for (int k = 0; k < i; ++k) v -= A[i * n + k] * b[k * 3 + c];
      b[i * 3 + c] = v / A[i * n + i];
    }
    for (int i = n - 1; i >= 0; --i) {  // L^T x = y
      double v = b[i * 3 + c];
      for (int k = i + 1; k < n; ++k) v -= A[k * n + i] * b[k * 3 + c];
      b[i * 3 + c] = v / A[i * n + i];
    }
  }
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(b[i])) return false;
  return true;
}

struct Channel {
  const float* v;
  const Guides::Guide* g;
};

// L consecutive pixels of a row at once, one lane each (doubles: the moment sums need
// the precision), every tap of the window in turn; the N x N moments of the L fits
// live in vectors, then each lane is solved on its own. Written over GCC vector
// extensions and compiled twice (generic, AVX2): taps of consecutive pixels are
// consecutive in every plane, so a tap is one unaligned load per plane.
template <int L>
struct VecD {
  typedef double d __attribute__((vector_size(8 * L)));
};

template <int N, int L>
MCR_INLINE void fit_group(const RegressionPass& a, const Channel* ch, int px0, int lanes, int y) {
  using vd = typename VecD<L>::d;
  using vf = typename simd::Vec<L>::f;
  constexpr int nf = N - 1;
  const PlaneBox& pb = a.pb;
  const Roi& box = pb.box;
  const std::size_t ip0 = pb.index(px0, y);
  auto loadf = [&](const float* plane, std::size_t i) {
    vf v;
    std::memcpy(&v, plane + i, sizeof v);
    return __builtin_convertvector(v, vd);
  };
  auto lane_or = [&](const float* plane, float c) {
    vd v;
    for (int l = 0; l < L; ++l) v[l] = plane && l < lanes ? plane[ip0 + std::size_t(l)] : (l < lanes ? c : 0.0f);
    return v;
  };
  vd fp[N > 1 ? nf : 1], sk[N > 1 ? nf : 1];
  for (int j = 0; j < nf; ++j) {
    const Guides::Guide* g = ch[j].g;
    fp[j] = lane_or(ch[j].v, 0.0f);
    const vd k = lane_or(g->k.empty() ? nullptr : g->k.data(), g->k_const);
    for (int l = 0; l < L; ++l) sk[j][l] = std::sqrt(k[l]);
  }
  const vd s = lane_or(a.s, a.s_const);
  const vd ca = a.colour_weight ? lane_or(a.colour_a, a.colour_a_const) * double(a.colour_amul) : vd{} + 0.0;
  vd g[3];
  for (int c = 0; c < 3; ++c) g[c] = a.colour_weight ? lane_or(a.guide[c], 0.0f) : vd{} + 0.0;
  // Window: the largest radius of the lanes; a lane ignores taps beyond its own.
  vd rl;
  int R = 0;
  for (int l = 0; l < L; ++l) {
    const int r = l < lanes ? (a.radius ? int(a.radius[ip0 + std::size_t(l)]) : a.rmax) : 0;
    rl[l] = r;
    R = std::max(R, r);
  }
  vd exists;  // 1 for the lanes that hold a pixel
  for (int l = 0; l < L; ++l) exists[l] = l < lanes ? 1.0 : 0.0;

  vd A[N * (N + 1) / 2], B[N * 3], wsum = vd{} + 0.0;
  for (vd& v : A) v = vd{} + 0.0;
  for (vd& v : B) v = vd{} + 0.0;
  vd lo[3], hi[3];
  for (int c = 0; c < 3; ++c) lo[c] = vd{} + DBL_MAX, hi[c] = vd{} - DBL_MAX;
  const int y0 = std::max(box.y0, y - R), y1 = std::min(box.y1 - 1, y + R);
  for (int qy = y0; qy <= y1; ++qy) {
    const double dy = qy - y;
    const vd ry = (vd{} + dy * dy) <= rl * rl ? vd{} + 1.0 : vd{} + 0.0;
    for (int dx = -R; dx <= R; ++dx) {
      const int qx0 = px0 + dx;  // lane l's tap is qx0 + l
      if (qx0 + lanes - 1 < box.x0 || qx0 >= box.x1) continue;
      // The planes' padding (kPlanePad zero columns, valid 0) covers up to 16 lanes
      // past either edge; beyond it, lanes outside the box are read one by one.
      const bool padded = qx0 >= box.x0 - kPlanePad && qx0 + L <= box.x1 + kPlanePad;
      const std::size_t iq = pb.index(padded ? qx0 : std::max(qx0, box.x0), qy);
      auto tap = [&](const float* plane) {
        if (padded) return loadf(plane, iq);
        vd v;
        for (int l = 0; l < L; ++l) {
          const int qx = qx0 + l;
          v[l] = qx >= box.x0 && qx < box.x1 ? plane[pb.index(qx, qy)] : 0.0f;
        }
        return v;
      };
      const vd valid = tap(a.valid);
      const vd inr = (vd{} + double(dx) * double(dx)) <= rl * rl ? vd{} + 1.0 : vd{} + 0.0;
      vd e = s * (vd{} + (dy * dy + double(dx) * double(dx)));
      vd x[N];
      x[0] = vd{} + 1.0;
      for (int j = 0; j < nf; ++j) {
        x[1 + j] = (tap(ch[j].v) - fp[j]) * sk[j];
        e += x[1 + j] * x[1 + j];
      }
      vd cq[3];
      for (int c = 0; c < 3; ++c) cq[c] = tap(a.colour[c]);
      if (a.colour_weight)
        for (int c = 0; c < 3; ++c) {
          const vd d = ca * (tap(a.guide[c]) - g[c]);
          e += d * d;
        }
      e = e < 1e30 ? e : vd{} + 1e30;  // also NaN -> 1e30 (weight 0)
      const vd w = __builtin_convertvector(simd::exp_neg_v<L>(__builtin_convertvector(e, vf)), vd) * valid * inr *
                   ry * exists;
      wsum += w;
      for (int c = 0; c < 3; ++c) {
        lo[c] = w > 0.0 ? (cq[c] < lo[c] ? cq[c] : lo[c]) : lo[c];
        hi[c] = w > 0.0 ? (cq[c] > hi[c] ? cq[c] : hi[c]) : hi[c];
      }
      int m = 0;
      for (int i = 0; i < N; ++i) {
        const vd wx = w * x[i];
        for (int k = 0; k <= i; ++k) A[m++] += wx * x[k];
        for (int c = 0; c < 3; ++c) B[i * 3 + c] += wx * cq[c];
      }
    }
  }
  for (int l = 0; l < lanes; ++l) {
    const std::size_t ip = ip0 + std::size_t(l);
    double Al[N * N], Bl[N * 3];
    int m = 0;
    for (int i = 0; i < N; ++i)
      for (int k = 0; k <= i; ++k) Al[i * N + k] = A[m++][l];
    for (int i = 0; i < N * 3; ++i) Bl[i] = B[i][l];
    for (int i = 1; i < N; ++i) Al[i * N + i] += a.ridge * wsum[l];
    const bool ok = (!a.feature_ok || a.feature_ok[ip] != 0.0f) && wsum[l] > 0.0 && cholesky_solve(Al, N, Bl);
    for (int c = 0; c < 3; ++c)
      a.out[c][ip] = ok ? float(std::clamp(Bl[c], lo[c][l], hi[c][l])) : a.fallback[c][ip];
  }
}

constexpr int kLanes = 4;

template <int N>
void rows_generic(const RegressionPass& a, const Channel* ch, int y, int x0, int x1) {
  for (int x = x0; x < x1; x += kLanes) fit_group<N, kLanes>(a, ch, x, std::min(kLanes, x1 - x), y);
}
template <int N>
MCR_TARGET_AVX2 __attribute__((flatten)) void rows_avx2(const RegressionPass& a, const Channel* ch, int y, int x0,
                                                        int x1) {
  for (int x = x0; x < x1; x += kLanes) fit_group<N, kLanes>(a, ch, x, std::min(kLanes, x1 - x), y);
}

template <int N>
void fit_rows(const RegressionPass& a, const Channel* ch, const Roi& region, int nthreads) {
  const bool avx2 = isa_at_least(Isa::Avx2);
  parallel_rows(region.y0, region.y1, nthreads, [&](int y) {
    if (avx2) rows_avx2<N>(a, ch, y, region.x0, region.x1);
    else rows_generic<N>(a, ch, y, region.x0, region.x1);
  });
}

}  // namespace

void feature_regression(const RegressionPass& a, const Roi& region, int nthreads) {
  std::vector<Channel> ch;
  for (const Guides::Guide* g : a.features)
    for (int c = 0; c < g->channels; ++c) ch.push_back({g->c[c].data(), g});
  const Channel* c = ch.data();
  static_assert(kMaxRegressors == 11, "one case per regressor count below");
  switch (1 + int(ch.size())) {
    case 1: return fit_rows<1>(a, c, region, nthreads);
    case 2: return fit_rows<2>(a, c, region, nthreads);
    case 3: return fit_rows<3>(a, c, region, nthreads);
    case 4: return fit_rows<4>(a, c, region, nthreads);
    case 5: return fit_rows<5>(a, c, region, nthreads);
    case 6: return fit_rows<6>(a, c, region, nthreads);
    case 7: return fit_rows<7>(a, c, region, nthreads);
    case 8: return fit_rows<8>(a, c, region, nthreads);
    case 9: return fit_rows<9>(a, c, region, nthreads);
    case 10: return fit_rows<10>(a, c, region, nthreads);
    case 11: return fit_rows<11>(a, c, region, nthreads);
    default: throw Error(Errc::Internal, "feature_regression: more than kMaxRegressors regressors");
  }
}

}  // namespace mcr
