#pragma once
// PixelWindow <-> OpenImageIO spec (data origin and display window).
#include <OpenImageIO/imageio.h>

#include "image/pass.h"

namespace mcr {

inline PixelWindow window_of(const OIIO::ImageSpec& spec) {
  return {spec.x, spec.y, spec.full_x, spec.full_y, spec.full_width, spec.full_height};
}

// Origin always; the display window only when one is set (full_width 0 = none).
inline void set_window(OIIO::ImageSpec& spec, const PixelWindow& w) {
  spec.x = w.x;
  spec.y = w.y;
  if (w.full_width > 0 && w.full_height > 0) {
    spec.full_x = w.full_x;
    spec.full_y = w.full_y;
    spec.full_width = w.full_width;
    spec.full_height = w.full_height;
  }
}

}  // namespace mcr
