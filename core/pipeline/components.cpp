#include "pipeline/components.h"

#include <cfloat>
#include <cmath>

#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

namespace {

// Blender's pass name of each light role, for messages.
const char* blender_name(Role r) {
  switch (r) {
    case Role::DiffuseDirect: return "DiffDir";
    case Role::DiffuseIndirect: return "DiffInd";
    case Role::DiffuseColour: return "DiffCol";
    case Role::GlossyDirect: return "GlossDir";
    case Role::GlossyIndirect: return "GlossInd";
    case Role::GlossyColour: return "GlossCol";
    case Role::TransmissionDirect: return "TransDir";
    case Role::TransmissionIndirect: return "TransInd";
    case Role::TransmissionColour: return "TransCol";
    case Role::Emission: return "Emit";
    case Role::Environment: return "Env";
    default: return role_name(r);
  }
}

// Non-finite as 0, +-inf as +-FLT_MAX.
float finite_or_zero(float v) {
  if (std::isnan(v)) return 0.0f;
  if (std::isinf(v)) return v > 0 ? FLT_MAX : -FLT_MAX;
  return v;
}

float clamped(float v) {
  if (std::isnan(v)) return 0.0f;
  return v > FLT_MAX ? FLT_MAX : v < -FLT_MAX ? -FLT_MAX : v;
}

}  // namespace

const std::vector<LightComponent>& light_components() {
  static const std::vector<LightComponent> list = {
      {"diffuse", "Diffuse", Role::DiffuseDirect, Role::DiffuseIndirect, Role::DiffuseColour, false},
      {"glossy", "Glossy", Role::GlossyDirect, Role::GlossyIndirect, Role::GlossyColour, true},
      {"transmission", "Transmission", Role::TransmissionDirect, Role::TransmissionIndirect, Role::TransmissionColour,
       true},
  };
  return list;
}

const std::vector<LightStage>& light_stages() {
  static const std::vector<LightStage> list = [] {
    std::vector<LightStage> l;
    for (std::size_t i = 0; i < light_components().size(); ++i) {
      if (!light_components()[i].split) {
        l.push_back({i, LightPart::Both});
        continue;
      }
      l.push_back({i, LightPart::Direct});
      l.push_back({i, LightPart::Indirect});
    }
    return l;
  }();
  return list;
}

std::string light_stage_name(const LightStage& stage) {
  const std::string name = light_components()[stage.component].name;
  switch (stage.part) {
    case LightPart::Direct: return name + " direct";
    case LightPart::Indirect: return name + " indirect";
    default: return name;
  }
}

const std::vector<std::string>& component_layer_names() {
  static const std::vector<std::string> names = {"Diffuse", "Glossy", "Transmission", "Emission", "Environment"};
  return names;
}

bool uses_light_passes(const ParamSet& params) {
  return params.has("components") && params.get_enum("components") == "light_passes";
}

void check_keep_components(const ParamSet& params) {
  if (uses_light_passes(params)) return;
  throw Error(Errc::InvalidArgument,
              "keep_components (--keep-components) writes the denoised light components and needs "
              "components=light_passes (the filter runs with components=" +
                  (params.has("components") ? params.get_enum("components") : std::string("beauty")) + ")");
}

std::string component_layer_prefix(const std::string& layer) {
  return layer.empty() ? "Denoised." : layer + ".Denoised.";
}

std::vector<Role> light_pass_roles() {
  std::vector<Role> roles;
  for (const LightComponent& c : light_components())
    for (Role r : {c.direct, c.indirect, c.colour}) roles.push_back(r);
  roles.push_back(Role::Emission);
  roles.push_back(Role::Environment);
  return roles;
}

void check_light_passes(const Frame& frame) {
  std::string missing;
  int count = 0;
  for (Role r : light_pass_roles())
    if (!frame.has(r)) {
      missing += (missing.empty() ? "" : ", ") + std::string(blender_name(r)) + " (" + role_name(r) + ")";
      ++count;
    }
  if (missing.empty()) return;
  throw Error(Errc::MissingPass,
              "components=light_passes needs Blender's light passes; " + std::string(count > 1 ? "these are" : "this is") +
                  " absent in '" + frame.path + "'" + (frame.layer.empty() ? "" : " (layer '" + frame.layer + "')") +
                  ": " + missing +
                  " (enable Diffuse, Glossy and Transmission Direct, Indirect and Color, Emission and Environment on the "
                  "view layer, or use components=beauty)");
}

Frame component_frame(const Frame& frame, const LightComponent& component, int nthreads, LightPart part,
                      bool remodulated) {
  Frame out = frame.header(frame.width, frame.height);
  out.window = frame.window;
  out.deep = frame.deep;
  const Pass& direct = frame.get(component.direct);
  const Pass& indirect = frame.get(component.indirect);
  for (const Pass& p : frame.passes) {
    switch (p.role) {
      case Role::Normal:
      case Role::Position:
      case Role::Depth:
      case Role::Motion:
      case Role::SecondPosition:
      case Role::SecondNormal:
      case Role::SampleCount:
      case Role::Alpha:
      // The colour passes describe the surface (prepare/surface_classes.h tells mirrors by them).
      case Role::DiffuseColour:
      case Role::GlossyColour: out.passes.push_back(p); break;
      default: break;  // colour, variance (the beauty's), the other light passes
    }
  }
  // The component's colour pass is its albedo feature (edge-stopping, guides): noise-free, it
  // tells metal from dielectric, where Blender's Denoising Albedo follows mirror bounces.
  Pass albedo = frame.get(component.colour);
  albedo.role = Role::Albedo;
  albedo.priority = 3;
  out.passes.push_back(std::move(albedo));
  Pass light;
  light.role = Role::Colour;
  light.name = part == LightPart::Direct     ? direct.name
               : part == LightPart::Indirect ? indirect.name
                                             : direct.name + "+" + indirect.name;
  light.source = direct.source;
  light.priority = 3;
  light.image = Image(frame.width, frame.height, 3);
  const Image& a = direct.image;
  const Image& b = indirect.image;
  const int ca = a.channels(), cb = b.channels();
  const bool with_a = part != LightPart::Indirect, with_b = part != LightPart::Direct;
  const Image& col = frame.image(component.colour);
  const int cc = col.channels();
  parallel_rows(0, frame.height, nthreads, [&](int y) {
    for (int x = 0; x < frame.width; ++x) {
      const float* pa = a.pixel(x, y);
      const float* pb = b.pixel(x, y);
      float* o = light.image.pixel(x, y);
      for (int c = 0; c < 3; ++c) o[c] = (with_a ? pa[c < ca ? c : 0] : 0.0f) + (with_b ? pb[c < cb ? c : 0] : 0.0f);
      if (remodulated)
        for (int c = 0; c < 3; ++c) o[c] = clamped(o[c] * finite_or_zero(col.at(x, y, c < cc ? c : 0)));
    }
  });
  out.passes.push_back(std::move(light));
  return out;
}

void add_light(Image& sum, const Image& part, int nthreads) {
  if (sum.width() != part.width() || sum.height() != part.height() || sum.channels() != part.channels())
    throw Error(Errc::Internal, "add_light: parts of different shape");
  const int w = sum.width(), ch = sum.channels();
  parallel_rows(0, sum.height(), nthreads, [&](int y) {
    float* s = sum.pixel(0, y);
    const float* p = part.pixel(0, y);
    for (int i = 0; i < w * ch; ++i) s[i] = clamped(s[i] + p[i]);
  });
}

Recombined recombine(const Frame& frame, const std::vector<Image>& filtered, int nthreads, bool remodulated) {
  const auto& comps = light_components();
  if (filtered.size() != comps.size())
    throw Error(Errc::Internal, "recombine: " + std::to_string(filtered.size()) + " filtered components");
  const int w = frame.width, h = frame.height;
  Recombined r;
  for (const std::string& name : component_layer_names()) r.layers.push_back({name, Image(w, h, 3)});
  r.beauty = Image(w, h, 3);
  std::vector<const Image*> colour;
  for (const LightComponent& c : comps) colour.push_back(&frame.image(c.colour));
  const Image& emit = frame.image(Role::Emission);
  const Image& env = frame.image(Role::Environment);
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float* sum = r.beauty.pixel(x, y);
      for (int c = 0; c < 3; ++c) sum[c] = 0.0f;
      auto add = [&](std::size_t layer, float v, int c) {
        r.layers[layer].rgb.at(x, y, c) = v;
        sum[c] = clamped(sum[c] + v);
      };
      for (std::size_t k = 0; k < comps.size(); ++k) {
        const float* light = filtered[k].pixel(x, y);
        const float* col = colour[k]->pixel(x, y);
        const int cc = colour[k]->channels();
        for (int c = 0; c < 3; ++c)
          add(k, clamped(remodulated ? light[c] : light[c] * finite_or_zero(col[c < cc ? c : 0])), c);
      }
      for (int c = 0; c < 3; ++c) add(comps.size(), finite_or_zero(emit.at(x, y, c < emit.channels() ? c : 0)), c);
      for (int c = 0; c < 3; ++c) add(comps.size() + 1, finite_or_zero(env.at(x, y, c < env.channels() ? c : 0)), c);
    }
  });
  return r;
}

}  // namespace mcr
