#pragma once
// The cross-bilateral filter of order 0 or 1 over the feature guides, with foveation: the
// body of the `bilateral` filter and the albedo prefilter's smoother (Immonen 2017, 3.4
// and 5.3; order=1: Moon et al. 2014, Bitterli et al. 2016):
//   out(p) = sum_q w(p,q) c(q) / sum_q w(p,q),
//   w(p,q) = exp(-|q-p|^2 / (2 spatial_sigma^2)) * prod_f exp(-|f(p)-f(q)|^2 / (2 f_sigma^2))
// over the square window |q-p| <= radius (clipped and renormalised at the borders), f in
// {colour, normal, position, albedo, depth}, each switched by use_<f>; order=1 replaces the
// weighted mean by a weighted first-order regression on the features over the same window
// (kernels/feature_regression.h), with the colour weight taken on the order-0 result.
#include <functional>
#include <string>
#include <vector>

#include "image/image.h"
#include "image/pass.h"
#include "kernels/feature_guides.h"
#include "kernels/planes.h"
#include "util/params.h"

namespace mcr {

// Its parameter table (spatial_sigma, radius, the feature block, colour_weight, order,
// ridge, foveation), without any preparation step's.
ParamTable cross_bilateral_fit_params();

// Scratch planes kept between calls (no page faults frame after frame).
struct CrossBilateralScratch {
  ColourPlanes cp;
  Guides guides;
  std::vector<float> valid, spatial, radius, res[3], reg[3];
  std::vector<float> noise_a;  // colour_weight=noise: per-pixel sqrt(k) of the colour weight
};

// How far around the roi the kernel may read the colour (and the albedo of its weights), an
// upper bound:
// the window (twice for order=1: its colour weight is taken on the order-0 result of the
// window), plus 3 px for the noise-relative colour weight's variance estimate.
int cross_bilateral_fit_reach(const ParamSet& params);

// Writes out inside roi; `params` holds cross_bilateral_fit_params() (and may hold more),
// `owner` names the filter in errors; note() receives dropped-weight notes. colour_units: the
// factor the colour was scaled by since an absolute colour_sigma was given in its units (the
// exposure step, prepare/exposure.h); a noise-relative weight needs none.
void cross_bilateral_fit(const Frame& frame, const Image& colour, const ParamSet& params, const std::string& owner,
                         const Roi& roi, Image& out, int nthreads, const std::function<void(std::string)>& note,
                         CrossBilateralScratch& scratch, double colour_units = 1.0);

}  // namespace mcr
