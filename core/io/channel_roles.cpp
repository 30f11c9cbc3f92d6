#include "io/channel_roles.h"

#include <algorithm>
#include <cctype>
#include <map>

namespace mcr {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

struct Alias {
  const char* name;  // lower-case pass name
  Role role;
  Space space;
  int priority;
};

// Blender names first; priority picks between candidates of one role
// (filters that want features get Denoising Albedo/Normal; see Frame::find).
const Alias kAliases[] = {
    {"combined", Role::Colour, Space::None, 3},        {"rgba", Role::Colour, Space::None, 2},
    {"rgb", Role::Colour, Space::None, 2},             {"color", Role::Colour, Space::None, 2},
    {"colour", Role::Colour, Space::None, 2},          {"beauty", Role::Colour, Space::None, 2},
    {"noisy", Role::Colour, Space::None, 1},           {"image", Role::Colour, Space::None, 1},
    {"denoising albedo", Role::Albedo, Space::None, 3}, {"albedo", Role::Albedo, Space::None, 2},
    {"texture", Role::Albedo, Space::None, 1},         {"diffcol", Role::Albedo, Space::None, 0},
    {"denoising normal", Role::Normal, Space::Camera, 3}, {"normal", Role::Normal, Space::World, 2},
    {"normals", Role::Normal, Space::World, 2},        {"n", Role::Normal, Space::World, 1},
    {"position", Role::Position, Space::World, 2},     {"world_position", Role::Position, Space::World, 2},
    {"p", Role::Position, Space::World, 1},            {"pos", Role::Position, Space::World, 1},
    {"depth", Role::Depth, Space::Camera, 3},          {"z", Role::Depth, Space::Camera, 2},
    {"denoising depth", Role::Depth, Space::Camera, 1},
    {"vector", Role::Motion, Space::None, 2},          {"motion", Role::Motion, Space::None, 2},
    {"motion_vector", Role::Motion, Space::None, 2},   {"velocity", Role::Motion, Space::None, 1},
    {"mv", Role::Motion, Space::None, 1},
    {"variance", Role::Variance, Space::None, 2},      {"denoising variance", Role::Variance, Space::None, 1},
    {"var", Role::Variance, Space::None, 1},
    {"second_position", Role::SecondPosition, Space::World, 2}, {"secondposition", Role::SecondPosition, Space::World, 2},
    {"second position", Role::SecondPosition, Space::World, 2}, {"position2", Role::SecondPosition, Space::World, 1},
    {"p2", Role::SecondPosition, Space::World, 1},
    {"second_normal", Role::SecondNormal, Space::World, 2}, {"secondnormal", Role::SecondNormal, Space::World, 2},
    {"second normal", Role::SecondNormal, Space::World, 2}, {"normal2", Role::SecondNormal, Space::World, 1},
    {"n2", Role::SecondNormal, Space::World, 1},
    {"sample_count", Role::SampleCount, Space::None, 2}, {"samplecount", Role::SampleCount, Space::None, 2},
    {"sample count", Role::SampleCount, Space::None, 2}, {"debug sample count", Role::SampleCount, Space::None, 1},
    {"samples", Role::SampleCount, Space::None, 1},    {"spp", Role::SampleCount, Space::None, 1},
    {"alpha", Role::Alpha, Space::None, 2},
    // Light passes: Blender's names, then the role names (plain files, loose files).
    {"diffdir", Role::DiffuseDirect, Space::None, 2},  {"diffind", Role::DiffuseIndirect, Space::None, 2},
    {"diffcol", Role::DiffuseColour, Space::None, 2},  {"glossdir", Role::GlossyDirect, Space::None, 2},
    {"glossind", Role::GlossyIndirect, Space::None, 2}, {"glosscol", Role::GlossyColour, Space::None, 2},
    {"transdir", Role::TransmissionDirect, Space::None, 2}, {"transind", Role::TransmissionIndirect, Space::None, 2},
    {"transcol", Role::TransmissionColour, Space::None, 2}, {"emit", Role::Emission, Space::None, 2},
    {"env", Role::Environment, Space::None, 2},
    {"diffuse_direct", Role::DiffuseDirect, Space::None, 1}, {"diffuse_indirect", Role::DiffuseIndirect, Space::None, 1},
    {"diffuse_colour", Role::DiffuseColour, Space::None, 1}, {"diffuse_color", Role::DiffuseColour, Space::None, 1},
    {"glossy_direct", Role::GlossyDirect, Space::None, 1}, {"glossy_indirect", Role::GlossyIndirect, Space::None, 1},
    {"glossy_colour", Role::GlossyColour, Space::None, 1}, {"glossy_color", Role::GlossyColour, Space::None, 1},
    {"transmission_direct", Role::TransmissionDirect, Space::None, 1},
    {"transmission_indirect", Role::TransmissionIndirect, Space::None, 1},
    {"transmission_colour", Role::TransmissionColour, Space::None, 1},
    {"transmission_color", Role::TransmissionColour, Space::None, 1},
    {"emission", Role::Emission, Space::None, 1},      {"environment", Role::Environment, Space::None, 1},
};

// Roles whose channels are read R,G,B first.
bool rgb_role(Role r) {
  switch (r) {
    case Role::Normal:
    case Role::Position:
    case Role::SecondPosition:
    case Role::SecondNormal:
    case Role::Albedo: return false;
    default: return true;
  }
}

// Channel suffix orders a role accepts, best first.
const std::vector<std::vector<std::string>>& orders(Role role) {
  static const std::vector<std::vector<std::string>> colour = {{"r", "g", "b"}, {"red", "green", "blue"}, {"x", "y", "z"}};
  static const std::vector<std::vector<std::string>> vec3 = {{"x", "y", "z"}, {"r", "g", "b"}, {"u", "v", "w"}};
  static const std::vector<std::vector<std::string>> vec2 = {{"x", "y"}, {"r", "g"}, {"u", "v"}};
  static const std::vector<std::vector<std::string>> scalar = {{"z"}, {"v"}, {"y"}, {"r"}, {"x"}, {"a"}};
  switch (role_channels(role)) {
    case 3: return rgb_role(role) ? colour : vec3;
    case 2: return vec2;
    default: return scalar;
  }
}

std::optional<std::vector<int>> pick(const ChannelGroup& g, Role role) {
  std::map<std::string, int> by_suffix;
  for (std::size_t i = 0; i < g.suffixes.size(); ++i) by_suffix[lower(g.suffixes[i])] = g.indices[i];
  for (const auto& order : orders(role)) {
    std::vector<int> idx;
    for (const auto& s : order) {
      auto it = by_suffix.find(s);
      if (it == by_suffix.end()) break;
      idx.push_back(it->second);
    }
    if (idx.size() == order.size()) {
      // Motion keeps Blender's Z,W (current minus next) when present.
      if (role == Role::Motion)
        for (const char* s : {"z", "w"})
          if (by_suffix.count(s)) idx.push_back(by_suffix[s]);
      return idx;
    }
  }
  // A single-channel group serves any scalar role whatever its suffix.
  if (role_channels(role) == 1 && g.indices.size() == 1) return std::vector<int>{g.indices[0]};
  return std::nullopt;
}

}  // namespace

std::string ChannelGroup::name() const {
  if (layer.empty()) return pass;
  return pass.empty() ? layer : layer + "." + pass;
}

std::vector<ChannelGroup> group_channels(const std::vector<std::string>& names) {
  std::vector<ChannelGroup> groups;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    std::string layer, pass, suffix = n;
    const auto last = n.rfind('.');
    if (last != std::string::npos) {
      suffix = n.substr(last + 1);
      const std::string prefix = n.substr(0, last);
      const auto mid = prefix.rfind('.');
      if (mid == std::string::npos) {
        pass = prefix;
      } else {
        layer = prefix.substr(0, mid);
        pass = prefix.substr(mid + 1);
      }
    }
    auto it = std::find_if(groups.begin(), groups.end(),
                           [&](const ChannelGroup& g) { return g.layer == layer && g.pass == pass; });
    if (it == groups.end()) {
      groups.push_back({layer, pass, {}, {}});
      it = groups.end() - 1;
    }
    it->indices.push_back(int(i));
    it->suffixes.push_back(suffix);
  }
  return groups;
}

std::optional<RoleMatch> force_role(const ChannelGroup& group, Role role) {
  if (auto idx = pick(group, role)) return RoleMatch{role, Space::None, 0, *idx};
  // Loose files: any group with enough channels, taken in file order.
  const int n = role_channels(role);
  if (int(group.indices.size()) >= n) {
    std::vector<int> idx(group.indices.begin(), group.indices.begin() + n);
    return RoleMatch{role, Space::None, 0, idx};
  }
  return std::nullopt;
}

std::vector<RoleMatch> classify_group(const ChannelGroup& group) {
  std::vector<RoleMatch> out;
  const std::string pass = lower(group.pass);
  if (pass.empty()) {
    // Bare channels of a plain file: R,G,B colour, A alpha, Z depth.
    for (Role role : {Role::Colour, Role::Alpha, Role::Depth}) {
      ChannelGroup sub;
      const char* want = role == Role::Alpha ? "a" : role == Role::Depth ? "z" : nullptr;
      for (std::size_t i = 0; i < group.suffixes.size(); ++i) {
        const std::string s = lower(group.suffixes[i]);
        if (want ? s == want : (s == "r" || s == "g" || s == "b")) {
          sub.indices.push_back(group.indices[i]);
          sub.suffixes.push_back(group.suffixes[i]);
        }
      }
      if (sub.indices.empty()) continue;
      if (auto idx = pick(sub, role)) out.push_back({role, role == Role::Depth ? Space::Camera : Space::None, 1, *idx});
    }
    return out;
  }
  // Every alias of the name: DiffCol is the diffuse colour pass and the albedo of last resort.
  for (const Alias& a : kAliases) {
    if (pass != a.name) continue;
    if (auto idx = pick(group, a.role)) {
      out.push_back({a.role, a.space, a.priority, *idx});
      if (a.role == Role::Colour) {
        ChannelGroup alpha;
        for (std::size_t i = 0; i < group.suffixes.size(); ++i)
          if (lower(group.suffixes[i]) == "a") { alpha.indices.push_back(group.indices[i]); alpha.suffixes.push_back("A"); }
        if (!alpha.indices.empty()) out.push_back({Role::Alpha, Space::None, a.priority, alpha.indices});
      }
    }
  }
  return out;
}

}  // namespace mcr
