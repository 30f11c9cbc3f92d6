#pragma once
// Colour variance estimated from the image alone (variance of the pixel value, mean over
// R, G, B), for pwaf's window sizes (Guo & Pan 2012, 3.2) and the noise-relative colour
// weight of bilateral and atrous:
//   e_c(q) = I_c(q) - mean of I_c over q's valid 8-neighbours (m of them, clipped at borders),
//   a high-pass residual that a locally linear signal does not reach. For noise of per-sample
//   variance s^2 and n(q) samples per pixel, Var e_c(q) = s^2 * a(q) with
//   a(q) = 1/n(q) + (1/m^2) * sum over those neighbours of 1/n.
//   s^2(p) = sum over q in the (2*radius+1)^2 window of p of mean_c e_c(q)^2 / sum of a(q),
//   v(p)   = s^2(p) / n(p).
// n comes from sample_count (1 channel) when given, clamped to >= 1 with non-finite read as 1;
// without it n = 1 everywhere, so v is the plain pixel variance. Invalid pixels (valid[i] == 0)
// take no part. A non-finite estimate reads as the largest double.
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace mcr {

// A full-size vector, filled inside region only (0 elsewhere); reads region grown by
// radius + 1.
std::vector<double> estimate_variance(const Image& colour, const std::vector<std::uint8_t>& valid,
                                      const Image* sample_count, int radius, const Roi& region, int nthreads);

}  // namespace mcr
