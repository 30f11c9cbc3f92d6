#include "filters/image/guided_guides.h"

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

}  // namespace mcr::guided
