#pragma once
// The preparation steps the base class runs before a filter's run(), in this order:
//   exposure         a render far from display exposure filtered scaled into it, the result
//                    scaled back after the step back (prepare/exposure.h): exposure
//   holes            pull-push fill of the unsampled pixels, every pass (thesis 5.1):
//                    holes = auto (sample_count == 0 where that pass exists) | none |
//                    sample_count | alpha (alpha == 0); then, for a filter that reads position
//                    or depth, the first-hit holes of those passes (prepare/first_hit.h)
//   albedo_prefilter the albedo pass smoothed before any use (prepare/albedo_prefilter.h):
//                    albedo_prefilter (range sigma, 0 = off), albedo_prefilter_position
//   demodulate       colour / albedo (prepare/demodulation.h), multiplied back after run():
//                    demodulate, albedo_floor
//   outliers         bright outliers clamped (prepare/outliers.h): firefly_k (0 = off),
//                    firefly_radius; then every channel clamped to [-clamp, clamp] (0 = off)
// and one step after run() and remodulation:
//   step_back        the result blended toward the input wherever it is not estimated to
//                    beat it (prepare/step_back.h): step_back, step_back_radius, step_back_noise
// A filter states which steps it takes (FilterInfo::steps); its parameter table gets the
// parameters of those steps only, and no filter reads them: run() receives their result.
// Each step works on the region the filter reads (the roi grown by its reach); outside
// the roi the output is the input colour, bit for bit (non-finite values there become 0:
// nothing non-finite leaves a filter).
#include <cstddef>
#include <string>
#include <vector>

#include "image/pass.h"
#include "util/params.h"

namespace mcr {

struct PrepSteps {
  bool holes = true, albedo_prefilter = true, demodulate = true, outliers = true, step_back = true, exposure = true;
  // The first-hit holes (with holes): set by the filter for a run that reads position or depth.
  bool first_hit = false;
  static PrepSteps none() { return {false, false, false, false, false, false, false}; }
};

// `own` followed by the parameters of the steps, then `components`.
// The common firefly_k's default (the outlier step): on by default, high enough that a
// render without fireflies keeps its mean luminance within 0.5%.
constexpr double kDefaultFireflyK = 8.0;

ParamTable with_preparation_params(ParamTable own, const PrepSteps& steps);

// The filters whose weights keep edges (bilateral, atrous, pwaf) default to step_back_noise
// = 0, by passes: 2 with an albedo pass, whose weights and demodulation carry texture through,
// so their results are sound where the noise estimate runs low and a step back there only
// brings noise back (chosen on the tune scenes room and glossy at 1-64 spp, 1 / 1.5 / 2 / 3:
// better at each step for the three, worse for gaussian and guided, whose blur crosses texture
// and is undone best by the estimate as it is; 2 is the cap); 1 without one (the per-sample
// scenes flattened to colour and depth: motion pwaf 0.052 with 1, 0.083 with 2). They also
// default to step_back_estimate = illumination: the noise estimated with the albedo divided
// out, which reads a texture's edges as noise no more (chosen on room and glossy; box and
// guided, whose blur crosses texture, were worse with it on the other stills).
void edge_keeping_step_back(ParamTable& t);
// step_back_noise as it applies to this frame (0: by passes, above).
double step_back_noise_for(const ParamSet& params, const Frame& frame);
// The albedo the step back estimates the noise under (step_back_estimate = illumination and
// the frame has an albedo pass), else null.
const Image* step_back_modulation(const ParamSet& params, const Frame& frame);

// `components` (beauty | light_passes), in every filter's table so that every front end
// takes it by the same name; the pipeline reads it (pipeline/components.h), no filter does.
ParamSpec components_param();
// `alpha` (filter | keep), in the tables of the filters that take a flat frame (not the per-sample
// ones) so that every front end takes it by the same name; the pipeline reads it
// (pipeline/alpha_stage.h), no filter does.
ParamSpec alpha_param();

// The passes the steps need under these settings (demodulate: albedo; holes=sample_count
// / alpha: that pass) and those they use when present (albedo_prefilter: albedo, normal,
// position; holes=auto: sample_count).
// `why` gets, per required pass, the setting that needs it ("demodulate=true").
void preparation_needs(const ParamSet& params, const PrepSteps& steps, std::vector<Role>& required,
                       std::vector<std::string>& why, std::vector<Role>& optional);

// "firefly_radius has no effect with firefly_k=0" for each setting given that changes
// nothing under the others.
std::vector<std::string> preparation_unused(const ParamSet& params, const PrepSteps& steps);

// What run() reads.
struct Prepared {
  const Frame* frame = nullptr;  // every pass after the steps (the input itself when none changed one)
  Image colour;                  // RGB: demodulated and outlier-clamped inside the work region
  Image divisor;                 // the demodulation divisor (RGB); empty when not demodulated
  std::vector<std::string> notes;
  Frame own;                     // storage when a step changed a pass
  std::size_t holes = 0;         // unsampled pixels filled
};

// Runs the steps over `work` (clipped to the frame). Throws MissingPass naming the frame's
// file for a pass a setting needs. exposure: the factor the exposure step chose (1: none);
// the caller measures it over the whole frame (a band cannot) and scales the result back.
void prepare(const Frame& frame, const ParamSet& params, const PrepSteps& steps, const Roi& work, int nthreads,
             Prepared& out, double exposure = 1.0);

// After run() wrote `out` (RGB, the frame's size) inside roi: remodulated inside roi, the
// input colour's RGB outside it, non-finite values replaced by 0 everywhere. Returns the
// number of values replaced.
std::size_t finish(const Prepared& prepared, const Image& input_colour, const Roi& roi, int nthreads, Image& out);

// The RGB of `colour` as its own 3-channel image (row-parallel copy).
Image rgb_copy(const Image& colour, int nthreads);

}  // namespace mcr
