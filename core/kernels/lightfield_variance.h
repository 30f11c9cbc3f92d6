#pragma once
// The variance of each pixel's unfiltered light-field estimate (its samples' mean weighted by
// the light or aperture, w(y1) w(y2)), from its own samples: what the light-field filters' step
// back weighs their result against (kernels/risk_blend.h).
//
//   strata: the pixel's l x l strata (by where each sample's y falls in [-L, L]^2) split in two
//           like a chequerboard, A and B: (mean_A - mean_B)^2 / 4, each half's mean weighted as
//           the whole. Unbiased for the stratified estimate's own variance (the plain sample
//           variance is not: stratification removes the strata's spread, 10x at 64 spp on a
//           penumbra), one degree of freedom per pixel: only a window's sum is meant to be read.
//   samples: the weighted samples' spread as if they were independent,
//           sum w^2 (f - mean)^2 / (sum w)^2 * n / (n - 1): an upper bound for stratified samples.
// With one sample a pixel (l = 1) neither exists: the variance is -1 (unknown: the blend leaves
// such pixels as filtered). Non-finite sample values were replaced on decode (image/lightfield.h).
#include "image/image.h"
#include "image/lightfield.h"

namespace mcr::lf {

enum class VarianceFrom { Strata, Samples };

// RGB variance per pixel, for the pixels of roi (-1 elsewhere), of lf's samples as the file
// holds them (kernels/lightfield_input.h: decoded_lightfield, not divided by a modulation).
Image estimate_variance(const LightField& lf, VarianceFrom from, const Roi& roi, int nthreads);

}  // namespace mcr::lf
