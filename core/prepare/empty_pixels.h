#pragma once
// Where nothing was rendered, nothing is written. Cycles' colour is premultiplied: a pixel with
// alpha 0 and colour 0 (the world of a transparent render, a shadow catcher's unshadowed floor)
// holds no light, and light a filter spreads into it from an object beside it (up to 0.05 on the
// product still at 16 spp) would be added to whatever the image is composited over: a glow
// around every object. A pixel with alpha 0 and some colour (emission over a transparent world)
// is filtered as any other.
#include <cstddef>

#include "image/image.h"

namespace mcr {

// Inside roi, every pixel whose alpha (first channel of `alpha`) is exactly 0 and whose input
// colour is exactly 0 in R, G and B gets 0 in out's R, G and B. Returns how many were changed.
// alpha, input and out: the frame's size (else nothing is done).
std::size_t keep_empty_pixels(const Image& alpha, const Image& input, const Roi& roi, Image& out);

}  // namespace mcr
