#pragma once
// The guide choices of the guided filter (guided.cpp): which passes, in which order, and
// how each pass is scaled.
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

}  // namespace mcr::guided
