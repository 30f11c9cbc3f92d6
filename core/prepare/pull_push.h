#pragma once
// Pull-push hole filling (Gortler et al. 1996), as the thesis (5.1, 5.2) uses it
// to fill the pixels a sparse (foveated) render did not sample.
#include <vector>

#include "image/image.h"

namespace mcr {

// Fills every pixel whose weight is 0 from the weighted pyramid of the others;
// pixels with weight 1 keep their value, fractional weights blend. Non-finite
// values count as holes. With no valid pixel at all the image becomes 0.
void pull_push_fill(Image& image, const std::vector<float>& weights, int nthreads = 0);

}  // namespace mcr
