#pragma once
// How bright a new sample may be before it enters a temporal history (issue 15: a 1-spp
// sample of 300 entered at weight 1 or 0.2 and stayed for frames).
//
// Per pixel p, over the other pixels q of its (2 radius + 1)^2 window clipped at the image
// (centre excluded) whose three channels are finite, n of them:
//   limit(p) = mu + max(k sd, 0.01 |mu|)      (n >= 3; +inf below)
// with mu, sd the mean and population deviation of their luminance: the bound of the
// outlier rule in prepare/outliers.h, so a firefly is cut to what its neighbours back,
// and a highlight several pixels wide (its neighbours bright too) is left alone. The
// accumulation (temporal/accumulation.h) lets a sample through above this when its own
// history backs it. Float window sums, each window added directly (no running sums); a
// centre that dwarfs its window is summed pixel by pixel in double: within 1e-3 of the
// rule in double, plenty for a bound.
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace mcr {

// limit: one float per pixel of rgb (resized), +inf where the window has fewer than 3
// finite neighbours, the largest float where the bound would overflow.
// fresh (when given): the same with k_fresh, in the same pass.
void firefly_limits(const Image& rgb, int radius, double k, int nthreads, std::vector<float>& limit, double k_fresh = 0,
                    std::vector<float>* fresh = nullptr);

// cap: per pixel of rgb (resized), the largest finite luminance of its 3x3 neighbourhood
// (centre included) where flags[i] & mask, +inf elsewhere: how bright a history the
// current frame backs (a TAA-style clip, one-sided) on pixels whose history is not trusted.
void neighbourhood_caps(const Image& rgb, const std::vector<std::uint8_t>& flags, std::uint8_t mask, int nthreads,
                        std::vector<float>& cap);

}  // namespace mcr
