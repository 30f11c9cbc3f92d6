#pragma once
// Local noise scales of a noisy colour image, estimated from the image alone (no variance
// pass, no second buffer), for the step back (prepare/step_back.h) and `auto`:
//
//   variance(p)  the variance of one pixel's noise (mean over R, G, B): the mean over the
//                (2*3+1)^2 window, the 2 axis directions d and R, G, B of
//                (y(q) - y(q - d)) (y(q) - y(q + d)), at least 0. For pixel-independent
//                noise of variance s^2 its expectation is s^2; a step edge adds exactly 0
//                (one factor is 0 on either side of it; along the axes this holds at a
//                corner where four regions meet and on a pixel staircase too, which a
//                diagonal would not), a ramp of slope g adds -g^2, so edges cancel and
//                smooth shading or a pixel filter's blur make it err low.
//                Outliers (below) take no part where they are rare (under 3% of a tile):
//                one firefly's sample would otherwise spread its energy over the window of
//                every pixel near it; where they are many (a 1-spp render lit by rare
//                paths) they are the noise itself and count.
//   median(p)    per-channel median of the finite pixels of the 3x3 neighbourhood.
//   relative(p)  a relative noise level sparse bright structure cannot inflate: the
//                median, over a tile (4x4 pixels grown by 4), of the 8-neighbour high-pass
//                residual energy divided by (median luminance^2 + 1e-3), times 1.27
//                (median -> mean of a chi^2_3/3).
//   robust(p,c)  channel c's noise variance from it: relative(p) (median_c(p)^2 + 1e-3),
//                at least (0.02 median_c(p))^2 (2% is below what anyone sees, and a
//                converged render still has a scale). Monte Carlo noise grows with the
//                value, so a dark channel next to a bright one keeps a small scale.
//   variance(p,c) variance(p) shared among the channels in the same proportion.
//   excess(p)    mean over R, G, B of the squared distance by which y(p) lies beyond the
//                range of its 8 finite neighbours, in units of robust(p, c);
//   detail(p)    only with a variance pass: y(p) lies beyond the range of its 8 neighbours
//                by more than 4 of its own standard deviations (the pass, mean over R, G,
//                B): its own samples agree that it stands out, so it is detail (a clean
//                render's aliasing), not a firefly, whose own samples disagree by about
//                its distance (one sample F of n: distance ~ F/n, own deviation ~ F/n).
//   outlier(p)   y(p) lies above the range of its 8 finite neighbours by more than 4
//                robust deviations (mean over R, G, B of the squared excess above it > 16
//                robust(p)), and is not detail(p): a firefly (or a one-pixel highlight); a
//                block's corner is not one. Only above: Monte Carlo's outliers are bright (a
//                rare path adds light), while a pixel below its neighbours is noise at an edge
//                or in a shadow that a filter's result need not fix (per-sample dof_garden's
//                largest losses to pwaf were dark corner pixels given the blur of their bright
//                side); the step back weighs it like any other pixel.
//
// Non-finite pixels take no part in any neighbourhood; at a non-finite pixel every scale
// is 0 and outlier is false. Deterministic: no reduction depends on the thread count.
#include <cstdint>
#include <vector>

#include "image/image.h"
#include "metrics/metrics.h"  // kRelMseEps

namespace mcr {

struct NoiseScales {
  Roi box;                          // where the vectors below hold values, row-major
  std::vector<float> variance;      // one per pixel (mean over R, G, B)
  std::vector<float> relative;      // one per pixel
  std::vector<float> median;        // three per pixel (RGB)
  std::vector<std::uint8_t> finite; // the pixel's RGB is finite
  std::vector<float> excess;        // mean over R, G, B of (distance beyond the neighbours' range)^2 / robust
  std::vector<std::uint8_t> detail;  // a variance pass says it stands out in its own samples
  std::vector<std::uint8_t> outlier; // excess above the range > kOutlierSigmas^2, not detail
  std::size_t at(int x, int y) const {
    return std::size_t(y - box.y0) * std::size_t(box.width()) + std::size_t(x - box.x0);
  }
  double robust(std::size_t i, int c) const;
  double robust(std::size_t i) const { return (robust(i, 0) + robust(i, 1) + robust(i, 2)) / 3.0; }
  double variance_of(std::size_t i, int c) const;
  // With a modulation (below): each pixel's albedo per channel, raised to the floor; else empty.
  std::vector<float> albedo;
};

constexpr double kOutlierSigmas = 4.0;  // outlier: further than this many robust deviations

// Scales for the pixels of `box` (clipped to the image); reads up to 12 pixels around it.
// colour: RGB in its first three channels. variance: a variance pass (the variance of each
// pixel's value: a renderer's, or (A - B)^2 / 4 from two half buffers), or null; where it
// is given, finite and >= 0, `variance` comes from it instead of the estimate from the
// image (exact in expectation, no signal in it): its mean over the channels, averaged over
// the same window relative to each pixel's level and scaled back to the pixel's (.cpp).
// modulation: an albedo pass, or null. Without a variance pass `variance` is then estimated on
// the illumination, colour / albedo (the demodulation's albedo, kernels/albedo_divisor.h, at the
// default floor but without its ceiling: raised to 0.01, non-finite read as 1; an emitter's
// albedo is its emission, whose picture is no noise),
// and variance_of scales it back by the pixel's albedo^2: texture the albedo explains (a thin
// mortar line, an anti-aliased checker edge) is a peak the colour's products read as noise.
// The medians, scales and outliers stay the colour's.
NoiseScales estimate_noise_scales(const Image& colour, const Roi& box, int nthreads, const Image* variance = nullptr,
                                  const Image* modulation = nullptr);

// detail(p) above for one pixel, without the rest of the estimate (the firefly clamp's keep
// mask): false where the pass or the pixel is not finite, or it has no finite neighbour.
bool stands_out_in_own_samples(const Image& colour, const Image& variance, int x, int y);

// The firefly clamp's keep mask (prepare/outliers.h): one byte per pixel of the frame, 1 where
// stands_out_in_own_samples() inside region, 0 elsewhere; empty when there is no variance pass or
// it is not the colour's size.
std::vector<std::uint8_t> detail_mask(const Image& colour, const Image* variance, const Roi& region, int nthreads);

}  // namespace mcr
