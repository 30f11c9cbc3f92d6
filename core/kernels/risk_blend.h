#pragma once
// Blending a filter's result f back toward its noisy input y where it is not estimated to
// beat it, given the variance v of each input pixel (the light-field filters: from the
// pixel's own samples, kernels/lightfield_variance.h).
//
// The blend y + a (f - y) has expected squared error v - 2 a v (1 - div f) + a^2 E|f - y|^2
// (Stein's lemma), least at a = v (1 - div f) / E|f - y|^2; with div f ~ 0 (a filter over
// many pixels) a = v / |f - y|^2, as sums over a (2 radius + 1)^2 window clipped to roi and
// R, G, B, each term weighted by 1 / (f^2 + 0.01) as relMSE weighs it, clamped to [0, 1].
// An unbiased filter has E|f - y|^2 ~ v: a ~ 1; a biased one (a sharp shadow edge widened)
// adds its squared bias and is stepped back from. A variance estimate that runs low steps
// back where it should not (a ~ estimate / truth): only give it one that errs high.
//
// Unlike prepare/step_back.h (for image filters, whose noise comes from the image), no
// per-pixel limits: the variance here is the pixel's own. Pixels whose variance is negative
// (unknown) or whose values are not finite take no part in a window and keep f.
#include "image/image.h"

namespace mcr {

// input, variance: RGB (first three channels), the frame's size; out: f, changed inside roi
// only. Returns the mean a over the roi's pixels.
double blend_by_risk(const Image& input, const Image& variance, const Roi& roi, int radius, int nthreads, Image& out);

}  // namespace mcr
