#pragma once
// components=light_passes: Blender's light passes denoised one by one (issue 15).
//
//   Combined = (DiffDir + DiffInd) DiffCol + (GlossDir + GlossInd) GlossCol
//            + (TransDir + TransInd) TransCol + Emit + Env
//
// The direct/indirect passes hold light already divided by their colour pass, so each
// component's light is filtered as it is, with the frame's feature passes, by a filter of
// its own (its own history for temporal filters, kept by the pipeline:
// pipeline/reconstruction.h), then multiplied by its colour pass. Diffuse light is filtered
// as direct + indirect; glossy and transmission light as direct and indirect apart, then
// added (light_stages()): on a mirror or through glass the direct light is a sharp image
// of a small lamp or sun and the indirect light the reflected or refracted scene, two
// signals of very different level and noise that one filter's firefly cut and noise
// estimate treat badly together (on the `metal` sample: mean relMSE of the mirror pixels
// 0.21 summed, 0.14 apart, with atrous). Emission
// and environment pass through unchanged. The beauty is the float sum of the five
// layers, in the order of component_layer_names(), so that the written layers add up to
// the written beauty exactly. No filter knows of this: it sees an ordinary frame.
#include <string>
#include <vector>

#include "image/pass.h"
#include "util/params.h"

namespace mcr {

struct LightComponent {
  const char* name;   // "diffuse": note prefix
  const char* layer;  // "Diffuse": output layer name
  Role direct, indirect, colour;
  bool split;  // direct and indirect light filtered apart (glossy, transmission)
};

// Diffuse, glossy, transmission.
const std::vector<LightComponent>& light_components();

// Which of a component's light one filter run sees.
enum class LightPart { Both, Direct, Indirect };

// One filter run of components=light_passes: a component's light, or a part of it.
struct LightStage {
  std::size_t component;  // index into light_components()
  LightPart part;
};

// The filter runs, in order: diffuse (direct + indirect), glossy direct, glossy indirect,
// transmission direct, transmission indirect.
const std::vector<LightStage>& light_stages();

// "diffuse", "glossy direct": the prefix of a stage's notes.
std::string light_stage_name(const LightStage& stage);

// "Diffuse", "Glossy", "Transmission", "Emission", "Environment": the layers recombine()
// gives, in the order they are summed.
const std::vector<std::string>& component_layer_names();

// components=light_passes in these settings (false for a table without the parameter).
bool uses_light_passes(const ParamSet& params);

// keep_components (--keep-components) asked for under these settings: throws
// InvalidArgument unless components=light_passes.
void check_keep_components(const ParamSet& params);

// "ViewLayer.Denoised." ("Denoised." for a plain file): the prefix of the component layers
// keep_components writes ("ViewLayer.Denoised.Diffuse.R", ...).
std::string component_layer_prefix(const std::string& layer);

// Every light pass: the three components' direct, indirect and colour passes, emission,
// environment.
std::vector<Role> light_pass_roles();

// Throws MissingPass naming every absent light pass (Blender's name and the role) and the
// file: Blender writes each pass it was asked for, so all must be there.
void check_light_passes(const Frame& frame);

// The frame a component's filter sees: colour = direct + indirect (RGB; only the direct or
// the indirect light for LightPart::Direct or Indirect), albedo = the
// component's colour pass, plus the frame's other feature passes (normal, position, depth,
// motion, second hit, sample count, alpha). The colour pass, not Blender's Denoising Albedo,
// which follows mirror bounces and holds highlights (~200 at a sun's reflection at 1 spp);
// the colour pass is smooth and tells metal from dielectric. Not the variance pass: it
// measures the beauty's noise, not this light's.
Frame component_frame(const Frame& frame, const LightComponent& component, int nthreads,
                      LightPart part = LightPart::Both, bool remodulated = false);

// sum += part, clamped to the float range (a component's filtered direct and indirect light).
void add_light(Image& sum, const Image& part, int nthreads);

struct ComponentImage {
  std::string name;  // from component_layer_names()
  Image rgb;
};

struct Recombined {
  std::vector<ComponentImage> layers;  // component_layer_names() order
  Image beauty;                        // their float sum, in that order
};

// filtered[i] (the light of light_components()[i], RGB) times its colour pass (as it is
// when `remodulated`: the filter multiplied it back itself), then
// emission and environment as they are; non-finite colour, emission or environment
// values count as 0 (an infinite one as +-FLT_MAX), products and sums are clamped to the
// float range: nothing non-finite leaves.
Recombined recombine(const Frame& frame, const std::vector<Image>& filtered, int nthreads, bool remodulated = false);

}  // namespace mcr
