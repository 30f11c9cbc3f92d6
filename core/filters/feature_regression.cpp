#include "filters/feature_regression.h"

#include <algorithm>
#include <cfloat>
#include <cmath>

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

void feature_regression(const RegressionPass& a, const Roi& region, int nthreads) {
  const PlaneBox& pb = a.pb;
  const Roi& box = pb.box;
  // Feature channels, flattened: plane and the guide it belongs to.
  struct Channel {
    const float* v;
    const Guides::Guide* g;
  };
  std::vector<Channel> ch;
  for (const Guides::Guide* g : a.features)
    for (int c = 0; c < g->channels; ++c) ch.push_back({g->c[c].data(), g});
  const int nf = int(ch.size());
  const int n = 1 + nf;

  parallel_rows(region.y0, region.y1, nthreads, [&](int y) {
    double A[kMaxRegressors * kMaxRegressors], B[kMaxRegressors * 3], x[kMaxRegressors];
    double fp[kMaxRegressors], sk[kMaxRegressors];
    for (int px = region.x0; px < region.x1; ++px) {
      const std::size_t ip = pb.index(px, y);
      auto fall_back = [&] {
        for (int c = 0; c < 3; ++c) a.out[c][ip] = a.fallback[c][ip];
      };
      if (a.feature_ok && a.feature_ok[ip] == 0.0f) {
        fall_back();
        continue;
      }
      for (int j = 0; j < nf; ++j) {
        const Guides::Guide* g = ch[std::size_t(j)].g;
        const double k = g->k.empty() ? g->k_const : g->k[ip];
        fp[j] = ch[std::size_t(j)].v[ip];
        sk[j] = std::sqrt(k);
      }
      const double s = a.s ? a.s[ip] : a.s_const;
      const int r = a.radius ? int(a.radius[ip]) : a.rmax;
      const double ca = a.colour_weight ? double(a.colour_a ? a.colour_a[ip] : a.colour_a_const) * a.colour_amul : 0.0;
      const double g0 = a.colour_weight ? a.guide[0][ip] : 0.0, g1 = a.colour_weight ? a.guide[1][ip] : 0.0,
                   g2 = a.colour_weight ? a.guide[2][ip] : 0.0;
      std::fill(A, A + n * n, 0.0);
      std::fill(B, B + n * 3, 0.0);
      double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
      double wsum = 0.0;
      const int y0 = std::max(box.y0, y - r), y1 = std::min(box.y1 - 1, y + r);
      const int x0 = std::max(box.x0, px - r), x1 = std::min(box.x1 - 1, px + r);
      for (int qy = y0; qy <= y1; ++qy) {
        const double dy2 = double(qy - y) * double(qy - y);
        for (int qx = x0; qx <= x1; ++qx) {
          const std::size_t iq = pb.index(qx, qy);
          if (a.valid[iq] == 0.0f) continue;
          double e = s * (dy2 + double(qx - px) * double(qx - px));
          for (int j = 0; j < nf; ++j) {
            x[1 + j] = (double(ch[std::size_t(j)].v[iq]) - fp[j]) * sk[j];
            e += x[1 + j] * x[1 + j];
          }
          if (a.colour_weight) {
            const double d0 = ca * (a.guide[0][iq] - g0), d1 = ca * (a.guide[1][iq] - g1), d2 = ca * (a.guide[2][iq] - g2);
            e += d0 * d0 + d1 * d1 + d2 * d2;
          }
          const double w = double(fast_exp_neg(float(std::min(e, 1e30))));
          if (w == 0.0) continue;
          x[0] = 1.0;
          const double cq[3] = {a.colour[0][iq], a.colour[1][iq], a.colour[2][iq]};
          for (int c = 0; c < 3; ++c) {
            lo[c] = std::min(lo[c], cq[c]);
            hi[c] = std::max(hi[c], cq[c]);
          }
          wsum += w;
          for (int i = 0; i < n; ++i) {
            const double wx = w * x[i];
            for (int k = 0; k <= i; ++k) A[i * n + k] += wx * x[k];
            B[i * 3 + 0] += wx * cq[0];
            B[i * 3 + 1] += wx * cq[1];
            B[i * 3 + 2] += wx * cq[2];
          }
        }
      }
      if (!(wsum > 0.0)) {
        fall_back();
        continue;
      }
      for (int i = 1; i < n; ++i) A[i * n + i] += a.ridge * wsum;
      if (!cholesky_solve(A, n, B)) {
        fall_back();
        continue;
      }
      for (int c = 0; c < 3; ++c) a.out[c][ip] = float(std::clamp(B[c], lo[c], hi[c]));
    }
  });
}

}  // namespace mcr
