#pragma once
// Weighted first-order regression on the feature passes (bilateral order=1): for
// every pixel p, over its window, with the cross-bilateral weight w(p,q),
//
//   min_beta  sum_q w(p,q) |c(q) - beta_0 - sum_j beta_j x_j(q)|^2 + lambda W sum_j beta_j^2,
//   x_j(q) = (f_j(q) - f_j(p)) sqrt(k_f(p))   (every channel of every feature guide),
//   W = sum_q w(p,q),  out(p) = beta_0, clamped to the range of the window's c(q) with w > 0,
//
// the "first-order" regression of Moon et al. 2014 and Bitterli et al. 2016 (NFOR)
// over bilateral weights. A weighted mean (order 0) averages an antialiased edge
// pixel's mix of two surfaces, or a texture ramp, with neighbours of other mixes;
// the linear model in the features reproduces it. Features are centred on p and
// scaled by their own weight's 1/(sqrt(2) sigma), so lambda is unit-free.
#include <vector>

#include "kernels/feature_guides.h"
#include "kernels/planes.h"

namespace mcr {

struct RegressionPass {
  PlaneBox pb;
  const float* colour[3] = {nullptr, nullptr, nullptr};  // the values fitted (sanitised planes)
  const float* valid = nullptr;                          // neighbour usable (0/1)
  // Colour weight: exp(-sum_c (a (g_p - g_q))^2) on these planes (the zero-order result:
  // weights from the noisy colour itself favour neighbours that share its noise).
  bool colour_weight = false;
  const float* guide[3] = {nullptr, nullptr, nullptr};
  const float* colour_a = nullptr;  // per-pixel a, else colour_a_const; times colour_amul
  float colour_a_const = 0.0f;
  float colour_amul = 1.0f;
  std::vector<const Guides::Guide*> features;  // weights and regressors
  const float* feature_ok = nullptr;            // 1 where every feature of p is finite
  const float* s = nullptr;                     // per-pixel spatial coefficient, else s_const
  float s_const = 0.0f;
  const float* radius = nullptr;                // per-pixel window radius, else rmax
  int rmax = 0;
  double ridge = 1e-3;                          // lambda
  // Where no fit can be made (a feature of p not finite, a singular system): this value.
  const float* fallback[3] = {nullptr, nullptr, nullptr};
  float* out[3] = {nullptr, nullptr, nullptr};
};

// Fills out[] for every pixel of `region` (inside pb.box). Sums and the solve are in
// double; the result is always finite (clamped to the window's range).
void feature_regression(const RegressionPass& pass, const Roi& region, int nthreads);

// Largest number of regressors (constant + 3 three-channel features + depth).
inline constexpr int kMaxRegressors = 11;

}  // namespace mcr
