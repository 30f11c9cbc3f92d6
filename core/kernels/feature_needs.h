#pragma once
// What the feature parameter block (use_<f>, <f>_sigma; kernels/cross_bilateral.h) and
// foveation (kernels/foveation.h) say about passes and settings, for a filter's needs()
// and unused-setting report.
#include <string>
#include <vector>

#include "image/pass.h"
#include "util/params.h"

namespace mcr {

// Passes the block requires (use_<f>=on) and uses when present (use_<f>=auto); every
// required one with its setting ("use_depth=on").
void feature_needs(const ParamSet& params, std::vector<Role>& required, std::vector<std::string>& why,
                   std::vector<Role>& optional);

// "<f>_sigma has no effect with use_<f>=off" (also its _outer twin) for the settings given.
std::vector<std::string> feature_unused(const ParamSet& params);

// Without foveated=true: every _outer twin, gaze_x, gaze_y, inner_radius, outer_radius given.
std::vector<std::string> foveation_unused(const ParamSet& params);

}  // namespace mcr
