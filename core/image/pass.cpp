#include "image/pass.h"

#include <algorithm>
#include <cctype>
#include <utility>

#include "util/error.h"

namespace mcr {

const char* role_name(Role r) {
  switch (r) {
    case Role::Colour: return "colour";
    case Role::Albedo: return "albedo";
    case Role::Normal: return "normal";
    case Role::Position: return "position";
    case Role::Depth: return "depth";
    case Role::Motion: return "motion";
    case Role::Variance: return "variance";
    case Role::SecondPosition: return "second_position";
    case Role::SecondNormal: return "second_normal";
    case Role::SampleCount: return "sample_count";
    case Role::Alpha: return "alpha";
    case Role::DiffuseDirect: return "diffuse_direct";
    case Role::DiffuseIndirect: return "diffuse_indirect";
    case Role::DiffuseColour: return "diffuse_colour";
    case Role::GlossyDirect: return "glossy_direct";
    case Role::GlossyIndirect: return "glossy_indirect";
    case Role::GlossyColour: return "glossy_colour";
    case Role::TransmissionDirect: return "transmission_direct";
    case Role::TransmissionIndirect: return "transmission_indirect";
    case Role::TransmissionColour: return "transmission_colour";
    case Role::Emission: return "emission";
    case Role::Environment: return "environment";
  }
  return "?";
}

std::optional<Role> role_from_name(const std::string& name) {
  std::string n;
  for (char ch : name) n += char(std::tolower(static_cast<unsigned char>(ch)));
  if (n == "color") return Role::Colour;
  const std::string us = "_color";  // diffuse_color, ...: the American spelling too
  if (n.size() > us.size() && n.compare(n.size() - us.size(), us.size(), us) == 0)
    n = n.substr(0, n.size() - us.size()) + "_colour";
  for (Role r : kAllRoles)
    if (n == role_name(r)) return r;
  return std::nullopt;
}

int role_channels(Role r) {
  switch (r) {
    case Role::Colour:
    case Role::Albedo:
    case Role::Normal:
    case Role::Position:
    case Role::SecondPosition:
    case Role::SecondNormal:
    case Role::DiffuseDirect:
    case Role::DiffuseIndirect:
    case Role::DiffuseColour:
    case Role::GlossyDirect:
    case Role::GlossyIndirect:
    case Role::GlossyColour:
    case Role::TransmissionDirect:
    case Role::TransmissionIndirect:
    case Role::TransmissionColour:
    case Role::Emission:
    case Role::Environment: return 3;
    case Role::Motion: return 2;
    case Role::Depth:
    case Role::Variance:
    case Role::SampleCount:
    case Role::Alpha: return 1;
  }
  return 1;
}

const char* space_name(Space s) {
  switch (s) {
    case Space::None: return "none";
    case Space::World: return "world";
    case Space::Camera: return "camera";
  }
  return "?";
}

const Pass* Frame::find(Role r, Prefer p) const {
  const Pass* best = nullptr;
  auto score = [p](const Pass& x) {
    // Geometry users need world space first; feature users take the filtered pass.
    int s = x.priority * 4;
    if (p == Prefer::Geometry && x.space == Space::World) s += 1000;
    return s;
  };
  for (const Pass& pass : passes)
    if (pass.role == r && (!best || score(pass) > score(*best))) best = &pass;
  return best;
}

const Pass& Frame::get(Role r, Prefer p) const {
  if (const Pass* pass = find(r, p)) return *pass;
  throw Error(Errc::MissingPass, std::string("no ") + role_name(r) + " pass in '" + path + "'" +
                                     (layer.empty() ? "" : " (layer '" + layer + "')"));
}

Pass with_pixels(const Pass& p, Image image) {
  Pass q;
  q.role = p.role;
  q.name = p.name;
  q.source = p.source;
  q.channels = p.channels;
  q.space = p.space;
  q.priority = p.priority;
  q.image = std::move(image);
  return q;
}

Frame Frame::header(int w, int h) const {
  Frame f;
  f.width = w;
  f.height = h;
  f.path = path;
  f.layer = layer;
  f.layers = layers;
  f.frame_number = frame_number;
  return f;
}

void Frame::put(Pass p) {
  // An explicit pass (override) replaces every candidate of its role.
  passes.erase(std::remove_if(passes.begin(), passes.end(),
                              [&](const Pass& x) { return x.role == p.role; }),
               passes.end());
  passes.push_back(std::move(p));
}

void Frame::check_sizes() const {
  for (const auto* list : {&passes, &extra})
    for (const Pass& pass : *list)
      if (pass.image.width() != width || pass.image.height() != height)
        throw Error(Errc::SizeMismatch,
                    std::string(role_name(pass.role)) + " pass '" + pass.name + "' from '" +
                        pass.source + "' is " + std::to_string(pass.image.width()) + "x" +
                        std::to_string(pass.image.height()) + " but the frame is " +
                        std::to_string(width) + "x" + std::to_string(height));
}

}  // namespace mcr
