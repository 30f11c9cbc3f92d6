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
// sample_offset halves, each stratified like the whole: on the four per-sample sample scenes
// this estimates the mean's true squared error within 1.1-1.5x, where the spread of the
// samples / n (independent samples assumed) over-states it 1.7-3.6x. A pixel with fewer than
// two finite samples gets NaN (the estimate from the image is used there). None when a colour
// channel is not among the deep channels.
std::optional<Pass> sample_halves_variance(const DeepSamples& deep, const Pass& colour);

}  // namespace mcr
