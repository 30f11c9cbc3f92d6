#pragma once
// BMFR's last stage on its own: temporal anti-aliasing (Karis 2014) of a planar RGB frame
// with its reprojected history (bmfr_taa.cpp). BmfrFilter runs it on the phase III
// result; the tests call it directly.
#include "image/image.h"
#include "temporal/reprojection.h"

namespace mcr {

// BmfrFilter's taa_* parameters.
struct TaaSettings {
  float alpha = 0.2f;       // taa_alpha: weight of the current frame in the blend
  bool catmull_rom = true;  // taa_history: Catmull-Rom lookup, else bilinear over the taps inside the frame
  bool ycocg = true;        // taa_clip: ycocg_variance, else rgb_minmax
  float gamma = 1.0f;       // taa_gamma: half-width of the variance box in standard deviations
  const float* alpha_floor = nullptr;  // per pixel (w x h): the blend weight is at least this, or none
};

// current, history, next: planar RGB (three planes of rep.width x rep.height). The history
// (the previous output) is looked up where rep.prev_x / prev_y place each pixel, only for
// pixels with a tap inside the frame (rep.inside), clipped to the current frame's 3x3
// neighbourhood and blended with it; a pixel without a history sample, or with a
// non-finite blend, takes the current value. Writes every pixel of `next` (the output and
// the next history) and, when `out` is given (interleaved RGB, same size), its roi in the
// same pass. The generic and the AVX2 build (util/isa.h) give the same bits.
void temporal_antialias(const TaaSettings& s, const Reprojection& rep, const float* current, const float* history,
                        float* next, int nthreads, Image* out = nullptr, const Roi& roi = {});

}  // namespace mcr
