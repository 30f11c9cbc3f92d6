#include "prepare/empty_pixels.h"

namespace mcr {

std::size_t keep_empty_pixels(const Image& alpha, const Image& input, const Roi& roi, Image& out) {
  const int w = out.width(), h = out.height();
  if (alpha.width() != w || alpha.height() != h || input.width() != w || input.height() != h || alpha.channels() < 1 ||
      input.channels() < 3 || out.channels() < 3)
    return 0;
  const Roi r = roi.clipped(w, h);
  std::size_t changed = 0;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) {
      const float* in = input.pixel(x, y);
      if (alpha.pixel(x, y)[0] != 0.0f || in[0] != 0.0f || in[1] != 0.0f || in[2] != 0.0f) continue;
      float* o = out.pixel(x, y);
      if (o[0] == 0.0f && o[1] == 0.0f && o[2] == 0.0f) continue;
      o[0] = o[1] = o[2] = 0.0f;
      ++changed;
    }
  return changed;
}

}  // namespace mcr
