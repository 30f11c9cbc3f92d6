#include "filters/image/guided_guides.h"

#include <cmath>

#include "kernels/feature_activity.h"
#include "util/error.h"

namespace mcr::guided {

namespace {

constexpr GroupSpec kNormal{Source::Normal, 3, true};
constexpr GroupSpec kDepth{Source::Depth, 1, false};
constexpr GroupSpec kPosition{Source::Position, 3, false};
constexpr GroupSpec kAlbedo{Source::Albedo, 3, true};

}  // namespace

const std::vector<GuideChoice>& guide_choices() {
  static const std::vector<GuideChoice> list = {
      {"normal_depth", {kNormal, kDepth}},
      {"normal", {kNormal}},
      {"depth", {kDepth}},
      {"position", {kPosition}},
      {"normal_position", {kNormal, kPosition}},
      {"albedo", {kAlbedo}},
      {"normal_albedo", {kNormal, kAlbedo}},
      {"normal_depth_albedo", {kNormal, kDepth, kAlbedo}},
      {"luminance", {{Source::Luminance, 1, false}}},
      {"colour", {{Source::Colour, 3, false}}},
      {"normal_depth_colour", {kNormal, kDepth, {Source::Colour, 3, false}}},
  };
  return list;
}

std::vector<std::string> guide_names() {
  std::vector<std::string> names;
  for (const GuideChoice& g : guide_choices()) names.push_back(g.name);
  return names;
}

const GuideChoice& find_choice(const std::string& name) {
  for (const GuideChoice& g : guide_choices())
    if (name == g.name) return g;
  throw Error(Errc::BadParameterValue, "filter 'guided': unknown guide '" + name + "'");
}

Role source_role(Source s) {
  switch (s) {
    case Source::Normal: return Role::Normal;
    case Source::Depth: return Role::Depth;
    case Source::Position: return Role::Position;
    case Source::Albedo: return Role::Albedo;
    case Source::Luminance:
    case Source::Colour: break;
  }
  return Role::Colour;
}

bool reads_pass(Source s) { return s != Source::Luminance && s != Source::Colour; }

std::vector<GroupSpec> active_groups(const GuideChoice& choice, const Frame& frame, double epsilon, int nthreads,
                                     const std::function<void(std::string)>& note) {
  std::vector<GroupSpec> kept;
  std::vector<std::string> dropped;
  const GroupSpec* smallest = nullptr;  // the present pass group with the fewest channels
  const Roi all = Roi::all(frame.width, frame.height);
  for (const GroupSpec& g : choice.groups) {
    if (!reads_pass(g.source)) {  // the colour itself: always kept
      kept.push_back(g);
      continue;
    }
    const Pass* pass = frame.find(source_role(g.source));
    if (!pass) {  // the default guide on a render without this pass (a chosen guide's are checked first)
      dropped.push_back(std::string(role_name(source_role(g.source))) + " pass is absent: left out of the guide");
      continue;
    }
    if (!smallest || g.channels < smallest->channels) smallest = &g;
    const Tolerance tol = g.unit ? Tolerance(constant_tolerance(std::sqrt(epsilon))) : Tolerance(0.0, 0.49e-5);
    const FeatureActivity a = feature_activity(pass->image, g.channels, all, tol, nthreads);
    if (a.kind == Activity::Varies) {
      kept.push_back(g);
      continue;
    }
    dropped.push_back(activity_note(role_name(pass->role), a, all, frame.width, frame.height, "left out of the guide"));
  }
  if (kept.empty() && smallest) {
    kept.push_back(*smallest);
    note("guided: no guide pass varies over the frame; the " + std::string(role_name(source_role(smallest->source))) +
         " pass stays as the guide (the result is the box-of-box mean of the colour)");
    return kept;
  }
  for (std::string& d : dropped) note("guided: " + d);
  return kept;
}

}  // namespace mcr::guided
