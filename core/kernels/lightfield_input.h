#pragma once
// The light-field filters' common front: the parameters they share (one spec each, the same
// name, range and help in every table) and the decoded light field of a frame.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "image/lightfield.h"
#include "image/pass.h"
#include "kernels/lightfield_rules.h"
#include "util/params.h"

namespace mcr::lf {

ParamSpec max_width_param();
ParamSpec reject_param();
ParamSpec normal_degrees_param();
ParamSpec smooth_radius_param();
ParamSpec bounds_radius_param();
ParamSpec fallback_param();
ParamSpec mu_param(bool fallback_only);
ParamSpec bins_param();
ParamSpec residual_k_param();
ParamSpec residual_radius_param();
ParamSpec step_back_param();
ParamSpec step_back_radius_param();
ParamSpec lens_light_param();
// residual_k as it applies to this effect and spp: -1 (the default) is 3 for depth of field and
// soft shadows, 1 where the step back follows it (step_back_for, 2 samples a pixel or more), 0
// for gi (residual_k_param says why).
double residual_k_for(const Options& o, LightFieldEffect effect, int spp);
// residual_radius as it applies to l x l samples a pixel: 0 (the default) is 2 for l <= 2, 1
// above (residual_radius_param says why).
int residual_radius_for(const Options& o, int l);
// step_back as it applies to this effect: ByEffect (the default) is Strata for soft shadows, Off
// for depth of field and gi (step_back_param says why).
Options::StepBack step_back_for(const Options& o, LightFieldEffect effect);

// Options from a ParamSet holding any of the parameters above (absent ones keep their defaults).
Options options_from(const ParamSet& params);

// The frame's light field: throws Error(MissingPass) naming `filter` and the file when the frame
// has no deep buffer or one without the light-field attribute (README: the light-field
// convention), Error(SizeMismatch) when it is not the frame's size; decode's errors pass through.
// With a modulation (image/lightfield.h), the samples come back divided by their pixel's mod
// (0 where the mod is 0): what the filters shear; remodulate() multiplies the result back.
// The frame's decoded light field is used as it is (read_frame decodes it once); a frame built
// in memory with only the deep buffer is decoded here.
std::shared_ptr<const LightField> lightfield_input(const Frame& frame, const std::string& filter);
// The same, with the samples as the file holds them (not divided by a modulation).
std::shared_ptr<const LightField> decoded_lightfield(const Frame& frame, const std::string& filter);
void remodulate(const LightField& lf, const Roi& roi, Image& out);

// What each light-field filter's run() does around its core: decode (and demodulate) the
// frame's light field, run `core`, multiply the modulation back, add back what it missed
// against each pixel's own samples (the frame's flat colour; residual_k), step back toward
// them where the filter is not estimated to beat them (step_back); returns the notes (the
// counts, the non-finite values replaced, the pixels that took their residual, the step back).
// Soft shadows through a lens (LightField::lens; Yan et al. 2015, appendix) run that twice:
// the light (each sample's value over its texture) as soft shadows, then the lens (each
// sample's texture times its light, lens_light) as depth of field, and step back toward the
// frame's flat colour at the end (step_back auto: strata).
using Core = void (*)(const LightField&, const Options&, const Roi&, int, Image&, Counts*);
std::vector<std::string> run_on_frame(const Frame& frame, const std::string& filter, const Options& o, const Roi& roi,
                                      int nthreads, Image& out, Core core, bool sheared);

}  // namespace mcr::lf
