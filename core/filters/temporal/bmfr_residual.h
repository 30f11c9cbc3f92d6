#pragma once
// BMFR's detail stage (bmfr_residual.cpp): what the blockwise fit cannot explain, added
// back where the accumulated frames show it beyond their noise.
//
// The fit is smooth in the features within each block, so a hard shadow on a flat wall (a
// tap's shadow cast by a sun) or light that no feature tells apart is averaged over the
// block. Phase I's accumulation (no spatial filter, several frames) still holds it. Per
// pixel p, over the (2 radius + 1)^2 window W around it (clipped to the frame):
//   r(q)  = accumulated(q) x albedo(q) - result(q)   (RGB; the residual of the result)
//   m, v  = the window's mean and variance of r (per channel), n its finite pixels
//   w     = clamp(1 - k v_l / (n m_l^2), 0, 1), with m_l, v_l the means over R, G, B
//   result(p) += w m
// w is the James-Stein shrinkage of the window's mean residual: where the residual is noise
// about 0 (the fit is right) n m_l^2 is about v_l and nothing is added; where it is a
// structure many times its noise w tends to 1 and the window's mean comes back. k widens
// the noise margin. Non-finite residuals take no part; a window without a finite one adds
// nothing; added values are clamped to the float range.
#include <cstddef>
#include <vector>

#include "image/image.h"

namespace mcr {

struct ResidualSettings {
  int radius = 2;
  double k = 3.0;
};

// accumulated: phase I's (w x h x 3; the demodulated illumination when albedo is given);
// albedo: w x h x 3 or null; result: planar RGB (three planes of w x h), changed in place;
// scratch: kept by the caller between frames (5 floats per pixel). Returns how many pixels
// took more than half of their window's mean residual.
std::size_t add_back_residual(const ResidualSettings& s, const Image& accumulated, const Image* albedo, float* result,
                              std::vector<float>& scratch, int nthreads);

}  // namespace mcr
