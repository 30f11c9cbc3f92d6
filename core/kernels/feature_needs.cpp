#include "kernels/feature_needs.h"

namespace mcr {

namespace {

struct BlockFeature {
  const char* name;
  Role role;
};
constexpr BlockFeature kBlock[] = {{"colour", Role::Colour},
                                   {"normal", Role::Normal},
                                   {"position", Role::Position},
                                   {"albedo", Role::Albedo},
                                   {"depth", Role::Depth}};

void given_unused(const ParamSet& params, const std::string& name, const std::string& why, std::vector<std::string>& out) {
  if (params.has(name) && params.was_set(name)) out.push_back(name + " has no effect " + why);
}

}  // namespace

void feature_needs(const ParamSet& params, std::vector<Role>& required, std::vector<std::string>& why,
                   std::vector<Role>& optional) {
  for (const BlockFeature& f : kBlock) {
    const std::string use = std::string("use_") + f.name;
    if (!params.has(use) || f.role == Role::Colour) continue;
    const std::string& mode = params.get_enum(use);
    if (mode == "on") {
      required.push_back(f.role);
      why.push_back(use + "=on");
    } else if (mode == "auto") {
      optional.push_back(f.role);
    }
  }
}

std::vector<std::string> feature_unused(const ParamSet& params) {
  std::vector<std::string> out;
  for (const BlockFeature& f : kBlock) {
    const std::string use = std::string("use_") + f.name;
    if (!params.has(use) || params.get_enum(use) != "off") continue;
    const std::string sigma = std::string(f.name) + "_sigma";
    given_unused(params, sigma, "with " + use + "=off", out);
    given_unused(params, sigma + "_outer", "with " + use + "=off", out);
  }
  return out;
}

std::vector<std::string> foveation_unused(const ParamSet& params) {
  std::vector<std::string> out;
  if (!params.has("foveated") || params.get_bool("foveated")) return out;
  for (const auto& kv : params.values()) {
    const std::string& n = kv.first;
    const bool outer = n.size() > 6 && n.compare(n.size() - 6, 6, "_outer") == 0;
    if (outer || n == "gaze_x" || n == "gaze_y" || n == "inner_radius" || n == "outer_radius")
      given_unused(params, n, "with foveated=false", out);
  }
  return out;
}

}  // namespace mcr
