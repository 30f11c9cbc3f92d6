#pragma once
// The step back: after a filter ran, its result is blended toward the input wherever it
// is not estimated to beat it, so a clean render is left nearly as it was and a filter's
// bias (a highlight spread into a dark neighbour, a shadow averaged away) is undone.
//
// For a result f of the noisy input y = x + n (noise variance s^2 per pixel), the blend
// y + a (f - y) has expected squared error a^2 E|f-y|^2 - 2 a s^2 (1 - div f) + s^2
// (Stein's lemma), smallest at a = s^2 (1 - div f) / E|f-y|^2. With div f ~ 0 (a filter
// that averages many pixels) a = s^2 / |f-y|^2, summed over a (2 radius + 1)^2 window and
// R, G, B, each channel weighted by 1 / (median_c^2 + 0.01) as relMSE weighs it, and
// clamped to [0, 1]. Then, per pixel (kernels/noise_scale.h for the scales):
//   - a firefly (outlier) takes the filter's value: removing it is the point;
//   - elsewhere a <= 16 robust_c / (f_c - median_c)^2 for every channel: the result may
//     not leave the 3x3 median by more than 4 robust deviations (it would have pulled
//     light from a neighbour);
//   - the blend is clamped to the 3x3 range of the input (fireflies read as their
//     median) widened by 2 robust deviations.
// With s^2 estimated within 2x of the truth the blend is never worse than the input in
// expectation; the estimate errs low on ramps and blur (less filtering), high on sharp
// highlights (which the per-pixel limits catch).
// The estimate is right at the median of a window but spreads around it (true / estimated over
// 9x9 windows of the sample stills at 4 spp: 10th-90th percentile 0.46-1.49, glossy to 3.2):
// with noise_scale 1, a window whose estimate runs low steps back from a sound result. Stein's
// risk of the blend with the variance scaled by k is s^2 - (2k - k^2) gain: with k <= 2 still no
// worse than the input where the estimate is right; a result that beats the input keeps a = 1
// (clamped) down to an estimate 1/k of the truth.
// With a variance pass (one draw of each pixel's variance, not a window mean) a is also taken
// over a window twice as wide and the larger kept: the narrow ratio scatters enough to blend the
// input's noise back where the result beats it everywhere (.cpp).
// Non-finite input pixels keep the filter's value and take no part in any window.
#include <cstddef>

#include "image/image.h"

namespace mcr {

struct StepBackStats {
  double mean_weight = 1.0;   // mean a over the roi's finite pixels (1 = the filter's result)
  double input_share = 0.0;   // fraction of those pixels with a < 0.5
  std::size_t fireflies = 0;  // outliers given to the filter
};

// input: the colour the filter was given (RGB in its first channels, the frame's size);
// out: the filter's RGB result, changed inside roi only; variance: the frame's variance
// pass or null (kernels/noise_scale.h).
// noise_scale: without a variance pass, the image's noise estimate is multiplied by it (at most
// 2: the blend of a biased result then still keeps the input's risk where the estimate is right;
// above 1 a sound filter keeps its result where the estimate runs low; see below).
// modulation: the albedo pass, or null: without a variance pass the noise is then estimated on
// colour / albedo (the albedo clamped to [0.01, 1], non-finite read as 1) and scaled back by
// albedo^2 per channel, so texture the albedo explains is not read as noise.
// metric_eps: relMSE's term (x - r)^2 / (r^2 + 0.01) in the units of `input`: 0.01 where the
// input is the render as it is, 0.01 k^2 where the exposure step (prepare/exposure.h) scaled it
// by k, so the blend weighs errors as relMSE does on the render itself.
StepBackStats step_back(const Image& input, const Roi& roi, int radius, int nthreads, Image& out,
                        const Image* variance = nullptr, double noise_scale = 1.0,
                        const Image* modulation = nullptr, double metric_eps = 0.01);

}  // namespace mcr
