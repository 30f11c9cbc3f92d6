#pragma once
// Firefly (outlier) suppression before filtering, a common option of every filter
// (firefly_k, firefly_radius in with_common_params). The detection rule is Guo & Pan
// 2012, 3.3 (as in pwaf's suppress_outliers); the repair here clamps instead of
// replacing, so a pixel keeps its colour ratios and loses only the excess:
//
//   over the other pixels q of p's (2r+1)^2 window clipped at the image (centre
//   excluded) whose three channels are finite, n of them:
//     mu, sd = mean and population standard deviation of their luminance Y(q)
//     lim    = mu + max(k sd, 0.01 |mu|)
//   if n >= 3, Y(p) > lim and lim > 0:  rgb(p) *= lim / Y(p)   (Y(p) becomes lim)
//
// Only bright spikes are touched (a dark pixel never changes); non-finite pixels are
// left as they are (each filter's own non-finite policy handles them). Every pixel is
// judged against the unmodified input, so the result does not depend on the order or
// the thread count. Y = 0.2126 R + 0.7152 G + 0.0722 B, sums in double.
#include "image/image.h"

namespace mcr {

// Returns the suppressed copy of the first three channels of `colour` (k <= 0: a plain
// copy). `clamped`, when given, receives the number of pixels clamped.
Image suppress_fireflies(const Image& colour, int radius, double k, int nthreads, std::size_t* clamped = nullptr);

}  // namespace mcr
