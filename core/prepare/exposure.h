#pragma once
// Exposure (preparation step, parameter `exposure`): the image filters' constants are on the
// scale of a render exposed for display (relMSE's + 0.01 in every risk weight, the noise
// estimate's relative floors, auto's `converged`); the sample scenes' mean luminance is 0.20
// to 0.56 (and at twice their exposure, 0.65 to 1.1, every filter's error on them moved by
// under 2%). Met at another scale they act otherwise: the same renders at 1/10 of their
// exposure took auto on dof 64 spp to 4x its error, at 1/100 guided on room 4 spp to 11x
// (README, "Exposure"). So with exposure = auto a render whose level lies outside
// [kExposureLow, kExposureHigh] is filtered scaled into it by a power of two and its result
// scaled back; inside it a render is filtered as it is (bit for bit as before).
//   level = the mean over the finite pixels of 0.2126 |R| + 0.7152 |G| + 0.0722 |B|
//   (absolute values: a negative channel cannot hide a bright one). An unbiased estimate of
//   the clean image's mean: the sample stills' levels agree within 2% from 1 spp to the
//   reference.
// Scaled by k: the colour's RGB (not its alpha), the light passes (diffuse, glossy and
// transmission direct and indirect, emission, environment) and the `clamp` setting; the
// variance pass by k^2. Albedo, colour passes, geometry and sample counts are not light.
// Values are clamped to +-FLT_MAX both ways; non-finite values stay as they are.
#include <cstddef>
#include <vector>

#include "image/image.h"
#include "image/pass.h"
#include "util/params.h"

namespace mcr {

constexpr double kExposureLow = 0.18;   // mid grey
constexpr double kExposureHigh = 1.0;

// The level's sums, row by row in frame order (a frame in bands adds its rows in the same
// order as the whole frame: the same level bit for bit).
struct ExposureLevel {
  double sum = 0;
  double count = 0;
  double least = 3.402823466e38, most = 0;  // the least nonzero and the greatest |R|, |G|, |B|
  // Rows [rows.y0, rows.y1) of colour (RGB in its first channels).
  void add(const Image& colour, const Roi& rows, int nthreads);
  // 0 where no pixel is finite.
  double level() const { return count > 0 ? sum / count : 0.0; }
};

// The factor the render is filtered at: the least power of two that brings the level into the
// band (below it: to [0.18, 0.36); above it: to (0.5, 1]), 1 inside it or for a level that is 0
// or not finite; but no finite value is moved beyond [2^-120, 2^120] (a frame that spans the
// float range is scaled less, or not). A power of two scales and scales back exactly, so a
// kept input comes back bit for bit and two exposures a power of two apart give the same
// result up to their scale.
double exposure_scale(const ExposureLevel& level);

// Whether a pass holds light (scaled by k; the variance by k^2).
bool scales_with_exposure(Role r);

// Every such pass of `frame` multiplied (k; variance k^2), clamped to +-FLT_MAX.
void scale_exposure(Frame& frame, double k, int nthreads);

// rgb inside roi divided by k (the filtered result back at the render's exposure).
void unscale_exposure(Image& rgb, const Roi& roi, double k, int nthreads);

// The `exposure` parameter (auto | off), in every image filter's table.
ParamSpec exposure_param();

}  // namespace mcr
