#pragma once
// Two half buffers of one render: the same pixel's samples split in two independent
// halves (Blender: the same seed, cycles.sample_offset 0 and N/2, N/2 samples each). Their
// mean is the full render; (A - B)^2 / 4 is, in expectation, the variance of that mean
// (Var((A + B) / 2) = (Var A + Var B) / 4 = E (A - B)^2 / 4), per pixel and channel, with
// no signal in it: the noise estimate the step back and `auto` use where it is given
// (kernels/noise_scale.h).
#include <optional>
#include <string>

#include "image/deep.h"
#include "image/pass.h"

namespace mcr {

// `first` with its colour (RGB, and alpha where both have it) replaced by the mean of both
// halves and a 3-channel variance pass added (replacing one it had). Every other pass both
// halves hold (same role, channel group and channels) is their mean too, where a renderer
// accumulates it over the samples (albedo, normal, light passes, alpha; a finite value where
// the other half's is not; a sample count is their sum): Blender's 8-spp halves of a 16-spp
// render average to its 16-spp albedo and normals, and a filter weighing neighbours by one
// half's alone lost 5-25% (bilateral on the sample halves). Depth, position, motion and the
// second-hit passes stay the first's: Blender writes them from the first sample only (the
// second half's depth is 1e10, its position 0), and one hit's geometry is not averaged across
// an edge. Passes without a role (--keep-passes) stay the first's. Throws SizeMismatch naming
// both files when their sizes differ, MissingPass when either has no colour pass.
Frame combine_halves(Frame first, const Frame& second);

// The same estimate from one file of independent per-sample data (a deep file without alpha,
// the per-sample convention): each pixel's finite samples of the colour's channels split in
// stored order into a first half A (n1 = n / 2 samples) and a second B (n2 = n - n1), and
// Var(mean) = (A - B)^2 n1 n2 / n^2 (= (A - B)^2 / 4 for even n). Stored order is render
// order (the add-on writes sub-render k as sample k), so the halves are Blender's
// sample_offset halves, each stratified like the whole. Stratified halves are not independent:
// with Var(mean of n) ~ n^-alpha (alpha 1 for independent samples, up to 2 for an edge crossing
// a pixel's strata), E (A - B)^2 / 4 = (2^alpha - 1) Var(mean), 3x for an edge. So the estimate
// is corrected per frame: each half's own halves estimate, as the variance of a mean of n
// samples, over the whole's reads 2^alpha (summed over the frame's pixels, R, G, B weighed by
// 1 / (mean^2 + 0.01) as relMSE weighs them); every pixel's estimate is divided by 2^alpha - 1,
// alpha read within [1, 2]. A pixel whose variance is one sample's (that sample's squared
// deviation from the mean is over half of all its samples', in any channel) is a rare path,
// which stratification does not make less variable: it keeps the plain estimate and takes no
// part in reading alpha (its halves read 2^alpha = 2 exactly with one bright sample). On 12
// per-sample renders of the sample scenes (16 spp) the plain estimate over-stated the mean's
// true squared error 1.03-1.49x, the corrected one 1.00-1.26x; the spread of the samples / n
// (independent samples assumed) over-states it 1.06-2.7x. A pixel with fewer than two finite
// samples gets NaN (the estimate from the image is used there). None when a colour channel is
// not among the deep channels.
std::optional<Pass> sample_halves_variance(const DeepSamples& deep, const Pass& colour);

}  // namespace mcr
