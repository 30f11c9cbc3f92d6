#pragma once
// Noise-relative colour weight for the edge-avoiding filters (bilateral, atrous):
// colour_weight = noise measures colour differences in units of the centre pixel's
// estimated noise standard deviation instead of radiance units, as SVGF (Schied et
// al. 2017) and pwaf's Gc (Guo & Pan 2012, 3.3) do:
//
//   w_c(p,q) = exp(-|c(p) - c(q)|^2 / (2 colour_sigma^2 s(p)^2))
//   s(p)^2   = 3 Gv(p) + 1e-6 Y(p)^2 + 1e-30
//
// Gv is the per-pixel colour variance (mean over R, G, B; 3 Gv is the expected
// |noise|^2 of an RGB value, so colour_sigma counts standard deviations per channel) estimated from the image
// alone by pwaf::estimate_variance with a 3x3 window (high-pass residuals against
// the 8-neighbour mean; per sample and divided by the sample count when the frame
// has a sample_count pass), then smoothed by the 3x3 binomial [1 2 1]^2/16 over
// the finite pixels (SVGF's variance prefilter). The floor keeps a noise-free pixel
// from dividing by zero. A filter uses it by multiplying the colour weight's
// sqrt(k) by 1/s(p): noise_relative_colour_a() makes that plane.
//
// So one colour_sigma (a count of standard deviations) suits dark and bright regions
// and quiet and noisy renders alike: a fixed radiance sigma blurs dark glossy
// reflections and leaves the noise of bright ones. Atrous' colour_sigma_decay still
// shrinks it pass by pass, as the noise of the passes' inputs shrinks.
#include <cstddef>
#include <vector>

#include "kernels/cross_bilateral.h"
#include "kernels/feature_guides.h"
#include "util/params.h"
#include "image/image.h"
#include "image/pass.h"

namespace mcr {

// Enum "colour_weight": absolute (colour_sigma in radiance units) | noise (in units of
// the estimated noise standard deviation). Default absolute.
ParamSpec colour_weight_param();

// s(p)^2 above for every pixel of `box` (absolute coordinates), row-major over the box.
// colour: the RGB the filter reads (after demodulation); sample_count may be null.
std::vector<double> noise_variance(const Image& colour, const Image* sample_count, const Roi& box, int nthreads);

// Per-pixel sqrt(k) of the colour weight laid out by g.pb: (g.colour_a[p] or
// g.colour_a_const) / s(p), clamped to [0, 1e18] (finite). Fills `a`, reusing its memory.
void noise_relative_colour_a(const Image& colour, const Image* sample_count, const Guides& g, int nthreads,
                             std::vector<float>& a);

// The colour weight of a CrossPass from `guides`, made noise-relative when the
// filter's colour_weight parameter says so (the plane is kept in `scratch`).
void set_colour_weight(CrossPass& pass, const Guides& guides, const ParamSet& params, const Frame& frame,
                       const Image& colour, int nthreads, std::vector<float>& scratch);

}  // namespace mcr
