#include "filters/feature_regression.h"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include "util/error.h"
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

}  // namespace

namespace {

struct Channel {
  const float* v;
  const Guides::Guide* g;
};

// Per-thread scratch of one window, structure of arrays (tap index innermost) so that
// the moment sums are dot products the compiler vectorises.
struct Window {
  std::vector<double> x;  // N planes of taps (x[0] unused: the constant 1)
  std::vector<double> c;  // 3 planes: the colour of each tap
  std::vector<double> wx; // N planes: w * x
  std::vector<float> e, w;
  void reserve(int n, int taps) {
    const std::size_t t = std::size_t(taps);
    if (x.size() < std::size_t(n) * t) x.resize(std::size_t(n) * t), wx.resize(std::size_t(n) * t);
    if (c.size() < 3 * t) c.resize(3 * t);
    if (e.size() < t) e.resize(t), w.resize(t);
  }
};

double dot(const double* a, const double* b, int n) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  int t = 0;
  for (; t + 4 <= n; t += 4) {
    s0 += a[t] * b[t];
    s1 += a[t + 1] * b[t + 1];
    s2 += a[t + 2] * b[t + 2];
    s3 += a[t + 3] * b[t + 3];
  }
  for (; t < n; ++t) s0 += a[t] * b[t];
  return (s0 + s1) + (s2 + s3);
}

double sum(const double* a, int n) {
  double s0 = 0, s1 = 0;
  int t = 0;
  for (; t + 2 <= n; t += 2) s0 += a[t], s1 += a[t + 1];
  if (t < n) s0 += a[t];
  return s0 + s1;
}

// One pixel's fit with N regressors known at compile time.
template <int N>
void fit_pixel(const RegressionPass& a, const Channel* ch, int px, int y, Window& win) {
  constexpr int nf = N - 1;
  const PlaneBox& pb = a.pb;
  const Roi& box = pb.box;
  const std::size_t ip = pb.index(px, y);
  auto fall_back = [&] {
    for (int c = 0; c < 3; ++c) a.out[c][ip] = a.fallback[c][ip];
  };
  if (a.feature_ok && a.feature_ok[ip] == 0.0f) return fall_back();
  double fp[N > 1 ? nf : 1], sk[N > 1 ? nf : 1];
  for (int j = 0; j < nf; ++j) {
    const Guides::Guide* g = ch[j].g;
    fp[j] = ch[j].v[ip];
    sk[j] = std::sqrt(double(g->k.empty() ? g->k_const : g->k[ip]));
  }
  const double s = a.s ? a.s[ip] : a.s_const;
  const int r = a.radius ? int(a.radius[ip]) : a.rmax;
  const double ca = a.colour_weight ? double(a.colour_a ? a.colour_a[ip] : a.colour_a_const) * a.colour_amul : 0.0;
  const double g0 = a.colour_weight ? a.guide[0][ip] : 0.0, g1 = a.colour_weight ? a.guide[1][ip] : 0.0,
               g2 = a.colour_weight ? a.guide[2][ip] : 0.0;
  const int y0 = std::max(box.y0, y - r), y1 = std::min(box.y1 - 1, y + r);
  const int x0 = std::max(box.x0, px - r), x1 = std::min(box.x1 - 1, px + r);
  const int cap = (y1 - y0 + 1) * (x1 - x0 + 1);
  win.reserve(N, cap);
  double* X = win.x.data();
  double* C = win.c.data();
  int T = 0;
  for (int qy = y0; qy <= y1; ++qy) {
    const double dy2 = double(qy - y) * double(qy - y);
    for (int qx = x0; qx <= x1; ++qx) {
      const std::size_t iq = pb.index(qx, qy);
      if (a.valid[iq] == 0.0f) continue;
      double e = s * (dy2 + double(qx - px) * double(qx - px));
      for (int j = 0; j < nf; ++j) {
        const double v = (double(ch[j].v[iq]) - fp[j]) * sk[j];
        X[std::size_t(1 + j) * std::size_t(cap) + std::size_t(T)] = v;
        e += v * v;
      }
      if (a.colour_weight) {
        const double d0 = ca * (a.guide[0][iq] - g0), d1 = ca * (a.guide[1][iq] - g1), d2 = ca * (a.guide[2][iq] - g2);
        e += d0 * d0 + d1 * d1 + d2 * d2;
      }
      win.e[std::size_t(T)] = float(std::min(e, 1e30));
      for (int c = 0; c < 3; ++c) C[std::size_t(c) * std::size_t(cap) + std::size_t(T)] = a.colour[c][iq];
      ++T;
    }
  }
  fast_exp_neg_n(win.e.data(), win.w.data(), T);
  double* WX = win.wx.data();
  double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
  double wsum = 0.0;
  for (int t = 0; t < T; ++t) {
    const double w = win.w[std::size_t(t)];
    WX[t] = w;
    wsum += w;
    if (w == 0.0) continue;  // the range clamp counts taps with weight only
    for (int c = 0; c < 3; ++c) {
      const double v = C[std::size_t(c) * std::size_t(cap) + std::size_t(t)];
      lo[c] = std::min(lo[c], v);
      hi[c] = std::max(hi[c], v);
    }
  }
  if (!(wsum > 0.0)) return fall_back();
  for (int i = 1; i < N; ++i) {
    const double* xi = X + std::size_t(i) * std::size_t(cap);
    double* wxi = WX + std::size_t(i) * std::size_t(cap);
    for (int t = 0; t < T; ++t) wxi[t] = WX[t] * xi[t];
  }
  double A[N * N], B[N * 3];
  for (int i = 0; i < N; ++i) {
    const double* wxi = WX + std::size_t(i) * std::size_t(cap);
    A[i * N] = i == 0 ? wsum : sum(wxi, T);  // x_0 = 1
    for (int k = 1; k <= i; ++k) A[i * N + k] = dot(wxi, X + std::size_t(k) * std::size_t(cap), T);
    for (int c = 0; c < 3; ++c) B[i * 3 + c] = dot(wxi, C + std::size_t(c) * std::size_t(cap), T);
  }
  for (int i = 1; i < N; ++i) A[i * N + i] += a.ridge * wsum;
  if (!cholesky_solve(A, N, B)) return fall_back();
  for (int c = 0; c < 3; ++c) a.out[c][ip] = float(std::clamp(B[c], lo[c], hi[c]));
}

template <int N>
void fit_rows(const RegressionPass& a, const Channel* ch, const Roi& region, int nthreads) {
  parallel_rows(region.y0, region.y1, nthreads, [&](int y) {
    thread_local Window win;  // grown only: no allocation per pixel
    for (int px = region.x0; px < region.x1; ++px) fit_pixel<N>(a, ch, px, y, win);
  });
}

}  // namespace

void feature_regression(const RegressionPass& a, const Roi& region, int nthreads) {
  std::vector<Channel> ch;
  for (const Guides::Guide* g : a.features)
    for (int c = 0; c < g->channels; ++c) ch.push_back({g->c[c].data(), g});
  const Channel* c = ch.data();
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
