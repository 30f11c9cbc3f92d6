#include "prepare/surface_classes.h"

#include <algorithm>

#include "util/parallel.h"

namespace mcr {

namespace {

// The largest channel of the first three (a pass of fewer repeats its last), -1 when
// any is not finite.
float max3(const Image& im, int x, int y) {
  const float* p = im.pixel(x, y);
  const int ch = im.channels();
  float m = -1.0f;
  for (int c = 0; c < 3; ++c) {
    const float v = p[std::min(c, ch - 1)];
    if (!(v - v == 0.0f)) return -1.0f;
    m = std::max(m, v);
  }
  return m;
}

}  // namespace

void classify_surfaces(const Frame& frame, int nthreads, SurfaceClasses& out) {
  const int w = frame.width, h = frame.height;
  out.flags.assign(std::size_t(w) * std::size_t(h), 0);
  const Pass* albedo = frame.find(Role::Albedo);
  const Pass* diffuse = frame.find(Role::DiffuseColour);
  const Pass* glossy = frame.find(Role::GlossyColour);
  out.colour_passes = diffuse && glossy;
  std::vector<std::size_t> light(std::size_t(std::max(h, 0)), 0), mirror(light.size(), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    std::uint8_t* f = out.flags.data() + std::size_t(y) * std::size_t(w);
    for (int x = 0; x < w; ++x) {
      if (albedo && max3(albedo->image, x, y) > 1.0f) {
        f[x] |= SurfaceClasses::kLightInAlbedo;
        ++light[std::size_t(y)];
      }
      if (out.colour_passes) {
        const float d = max3(diffuse->image, x, y), g = max3(glossy->image, x, y);
        if (d >= 0.0f && g > kMirrorGloss && g > kMirrorRatio * d) {
          f[x] |= SurfaceClasses::kMirror;
          ++mirror[std::size_t(y)];
        }
      }
    }
  });
  out.light_in_albedo = out.mirror = 0;
  for (std::size_t i = 0; i < light.size(); ++i) {
    out.light_in_albedo += light[i];
    out.mirror += mirror[i];
  }
}

}  // namespace mcr
