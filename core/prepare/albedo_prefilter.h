#pragma once
// Albedo prefiltering (common parameter albedo_prefilter): the albedo pass of a
// 16-spp render carries noise of its own (pixel coverage at texture edges, the
// glossy bounces Blender's Denoising Albedo follows), and demodulation multiplies
// it back into the result. Feature prefiltering as in Bitterli et al. 2016 (NFOR,
// 4.1): log(max(albedo, floor)) is smoothed by a cross-bilateral first-order fit on
// the normal and position passes (bilateral order=1, spatial sigma 1 px), range
// sigma in log albedo so that bright and dark textures keep their edges alike. It runs the
// cross-bilateral kernel (kernels/cross_bilateral_fit.h), not the bilateral filter.
#include "image/image.h"
#include "image/pass.h"

namespace mcr {

struct AlbedoPrefilter {
  double range_sigma = 0.2;       // log-albedo units
  double position_sigma = 0.03;   // scene units
  double floor = 0.01;             // of the log (the albedo_floor default)
};

// The albedo, the size and channel count of `albedo`, smoothed inside roi (reading up to
// 6 px around it); a pixel whose albedo is not finite keeps its value (demodulation then
// uses 1 there, as without it), and so does every pixel outside roi.
Image prefilter_albedo(const Frame& frame, const Pass& albedo, const AlbedoPrefilter& p, const Roi& roi, int nthreads);

}  // namespace mcr
