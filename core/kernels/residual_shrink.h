#pragma once
// What a smoothing filter missed, added back where an unbiased estimate shows it beyond its
// noise (residual_shrink.cpp). Used by bmfr's detail stage (its fit against phase I's
// accumulation) and by the light-field filters (their result against each pixel's own
// samples).
//
// A filter that smooths with a model (bmfr's blockwise fit in the features) or a wide
// window (a sheared light-field filter at a penumbra) averages away what the model cannot
// hold: a hard shadow on a flat wall, a shadow edge its slopes misplace. The unbiased
// estimate (phase I's accumulation, a pixel's own samples) still holds it, under noise. Per
// pixel p, over the (2 radius + 1)^2 window W around it (clipped to the region filtered):
//   r(q)  = unbiased(q) x albedo(q) - result(q)   (RGB; the residual of the result)
//   m, v  = the window's mean and variance of r (per channel), n its finite pixels
//   w     = clamp(1 - k v_l / (n m_l^2), 0, 1), with m_l, v_l the means over R, G, B
//   result(p) += w m
// w is the James-Stein shrinkage of the window's mean residual: where the residual is noise
// about 0 (the result is right) n m_l^2 is about v_l and nothing is added; where it is a
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

// Where a pixel's RGB lies in a buffer: channel c of pixel i (row-major) at
// data[i * pixel_stride + c * channel_stride]: interleaved RGB {3, 1}, planar {1, w h}.
struct RgbLayout {
  float* data;
  std::size_t pixel_stride, channel_stride;
};

// unbiased: w x h x 3 (or more channels; the first three are read); albedo: w x h x 3 or
// null; result: the filter's (w x h), changed in place inside roi only, its windows clipped
// to roi (nothing outside is read); scratch: kept by the caller between frames (5 floats per
// pixel of roi). Returns how many pixels took more than half of their window's mean residual.
std::size_t add_back_residual(const ResidualSettings& s, const Image& unbiased, const Image* albedo, RgbLayout result,
                              const Roi& roi, std::vector<float>& scratch, int nthreads);

}  // namespace mcr
