#pragma once
// The one outlier rule (Guo & Pan 2012, 3.3) and its repairs. Over the other pixels q of
// p's (2r+1)^2 window clipped at the image (centre excluded) whose three channels are
// finite, n of them:
//   mu, sd = mean and population standard deviation (two passes) of their luminance Y(q)
//   p is a bright outlier iff n >= 3 and Y(p) - mu > k sd and Y(p) - mu > 0.01 |mu|
// Only bright spikes count (a dark pixel never does). Every pixel is judged against the
// unmodified input, so results do not depend on the order or the thread count.
//
// Repairs:
//   clamp_fireflies   (preparation step, common firefly_k / firefly_radius) scales an
//                     outlier's RGB down so that Y(p) becomes mu + max(k sd, 0.01 |mu|):
//                     it keeps its colour ratios and loses only the excess; non-finite
//                     pixels are left to the filter's own policy
//   replace_outliers  (pwaf's 3.3) replaces an outlier, and any pixel with a non-finite
//                     channel, by the mean RGB of those finite neighbours
//   clamp_channels    (common clamp) every finite channel to [-clamp, clamp]
#include <cstddef>
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace mcr {

// In place on the RGB `colour`, pixels inside roi only (the windows read around it).
// Returns the number of pixels clamped. k <= 0: nothing. keep: optional, one per pixel of
// the image; a pixel with keep 1 is never clamped (detail by a variance pass).
std::size_t clamp_fireflies(Image& colour, int radius, double k, const Roi& roi, int nthreads,
                            const std::vector<std::uint8_t>* keep = nullptr);

// Inside roi (pixels outside are copied from colour). A non-finite pixel with no finite
// neighbour is set to 0 and marked invalid (valid[i] = 0); every other pixel is valid.
// replaced[i] = 1 where an outlier was replaced, 2 where a non-finite pixel was. k <= 0
// disables the outlier rule (the non-finite repair stays).
struct OutlierResult {
  Image colour;                        // full size; the replaced image inside region
  std::vector<std::uint8_t> valid;     // full size, 1 outside region too
  std::vector<std::uint8_t> replaced;  // full size
};
OutlierResult replace_outliers(const Image& colour, int radius, double k, const Roi& roi, int nthreads);

// In place, inside roi: every finite channel clamped to [-lim, lim]; non-finite values kept.
void clamp_channels(Image& colour, double lim, const Roi& roi, int nthreads);

}  // namespace mcr
