#pragma once
// Two half buffers of one render: the same pixel's samples split in two independent
// halves (Blender: the same seed, cycles.sample_offset 0 and N/2, N/2 samples each). Their
// mean is the full render; (A - B)^2 / 4 is, in expectation, the variance of that mean
// (Var((A + B) / 2) = (Var A + Var B) / 4 = E (A - B)^2 / 4), per pixel and channel, with
// no signal in it: the noise estimate the step back and `auto` use where it is given
// (kernels/noise_scale.h).
#include "image/pass.h"

namespace mcr {

// `first` with its colour's RGB replaced by the mean of both halves (other channels and
// every other pass from `first`: Blender writes depth and position on the first sample
// only, so the second half's are not usable) and a 3-channel variance pass added
// (replacing one it had). Throws SizeMismatch naming both files when their sizes differ,
// MissingPass when either has no colour pass.
Frame combine_halves(Frame first, const Frame& second);

}  // namespace mcr
