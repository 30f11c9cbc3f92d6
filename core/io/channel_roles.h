#pragma once
// Finding pass roles from channel names: Blender multilayer ("ViewLayer.Normal.X"),
// plain single-layer EXRs ("R", "N.X", "albedo.R", "Z") and custom names.
#include <optional>
#include <string>
#include <vector>

#include "image/pass.h"

namespace mcr {

// Channels sharing a prefix: "ViewLayer.Denoising Normal.{X,Y,Z}" is one group
// with layer "ViewLayer", pass "Denoising Normal".
struct ChannelGroup {
  std::string layer;  // "" for plain files
  std::string pass;   // "" for bare R,G,B,A,Z
  std::vector<int> indices;            // into the file's channel list
  std::vector<std::string> suffixes;   // "R", "X", ...
  std::string name() const;            // "ViewLayer.Normal", "Normal", ""
};

std::vector<ChannelGroup> group_channels(const std::vector<std::string>& channel_names);

// A role found in a group: which of the group's channels, in the role's order.
struct RoleMatch {
  Role role;
  Space space = Space::None;
  int priority = 0;
  std::vector<int> indices;  // file channel indices, role order (R,G,B / X,Y,Z / ...)
};

// Roles a group provides. A bare group ("R","G","B","A","Z") can give several
// (colour, alpha, depth); a named group gives at most its role (plus alpha for RGBA colour).
std::vector<RoleMatch> classify_group(const ChannelGroup& group);

// Channels of a group read as `role` even when the group's name says nothing
// (a loose file "normals.exr" holding R,G,B); nullopt when it has too few.
std::optional<RoleMatch> force_role(const ChannelGroup& group, Role role);

}  // namespace mcr
