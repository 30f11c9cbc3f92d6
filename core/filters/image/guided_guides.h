#pragma once
// The guide choices of the guided filter (guided.cpp): which passes, in which order, and
// how each pass is scaled.
#include <functional>
#include <string>
#include <vector>

#include "image/pass.h"

namespace mcr::guided {

enum class Source { Normal, Depth, Position, Albedo, Luminance, Colour };

struct GroupSpec {
  Source source;
  int channels;
  bool unit;  // s = max(1, rms std) (unit quantities) instead of s = rms std
};

struct GuideChoice {
  const char* name;
  std::vector<GroupSpec> groups;
};

// Every choice, in the order of the parameter table.
const std::vector<GuideChoice>& guide_choices();
std::vector<std::string> guide_names();
// Throws BadParameterValue for an unknown name.
const GuideChoice& find_choice(const std::string& name);
// The pass a source reads (Colour for the colour-based ones, which read no pass).
Role source_role(Source s);
bool reads_pass(Source s);

// The groups of `choice` that carry information in `frame` (kernels/feature_activity.h),
// in order. A pass group is left out, with a note, when the frame lacks its pass (the default
// guide only: a guide the user chose needs its passes, GuidedFilter::own_needs), has no finite value or
// is constant over the frame: within 0.004 sqrt(epsilon) for normal and albedo (scaled
// by max(1, std), so a spread t moves the ridge solution by about t^2 / epsilon, under
// 2e-5), within 0.49e-5 relative (float rounding) for depth and position, which are
// divided by their own std. A constant guide channel is centred to 0 and gets
// coefficient 0: leaving it out gives the same output, with fewer channels to sum. When
// every group would go, the one with the fewest channels stays (the result is then the
// box-of-box mean either way).
std::vector<GroupSpec> active_groups(const GuideChoice& choice, const Frame& frame, double epsilon, int nthreads,
                                     const std::function<void(std::string)>& note);

}  // namespace mcr::guided
