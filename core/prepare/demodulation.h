#pragma once
// Albedo demodulation (preparation step `demodulate`, and bmfr's own fused one): the
// colour is divided by the albedo so a filter smooths the illumination, not the
// texture, and multiplied back after. One rule for every user:
//   a = min(max(albedo, floor), ceiling) where the albedo is finite, 1 where it is not;
//   a = max(a, |colour| * 2^-126) where the colour is finite;
// and dividing and multiplying by the same value is exact.
// The ceiling (kAlbedoCeiling = 1 for the image filters): a reflectance is at most 1, so
// an albedo above 1 holds light, not texture (Blender's Denoising Albedo follows a
// mirror's bounce: where that sample hit a lamp or the sun it reads ~200, the next
// sample 0.4). Divided by such a value a spatial filter would take the neighbour's
// illumination and remodulation would multiply it by 200; capped, such a pixel is not
// demodulated in that channel and its light stays in the illumination, where the outlier
// rules and the step back see it. bmfr passes no ceiling (+inf) and leaves such pixels
// out of its fit instead (filters/temporal/bmfr.h): its history is reprojected
// bilinearly, and an undivided highlight would bleed into the neighbours' histories.
// The second line keeps colour / a within 2^126, so a finite colour near FLT_MAX over a dark albedo does not
// overflow to inf (and come back as 0); it never acts below |colour| = 2^126 * a (8.5e37 a),
// so ordinary images are divided by the albedo as they always were.
#include "image/image.h"
#include "kernels/albedo_divisor.h"

namespace mcr {

// One row of n pixels: al = the divisor per channel (an albedo of fewer than 3 channels
// repeats its last one), il = colour / al. colour, al and il are RGB.
void demodulate_row(const float* albedo, int albedo_channels, const float* colour, int n, float floor, float* al,
                    float* il, float ceiling = kAlbedoCeiling);

// Inside roi: divisor(x, y) = the rule above on `albedo`, colour(x, y) /= divisor. Both
// RGB, the frame's size; pixels outside roi are not touched.
void demodulate(const Image& albedo, float floor, const Roi& roi, int nthreads, Image& divisor, Image& colour);

}  // namespace mcr
