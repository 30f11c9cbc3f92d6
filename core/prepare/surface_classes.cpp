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
  const Pass* normal = frame.find(Role::Normal, Prefer::Geometry);  // the one the reprojection reads
  std::vector<std::size_t> light(std::size_t(std::max(h, 0)), 0), mirror(light.size(), 0), background(light.size(), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    std::uint8_t* f = out.flags.data() + std::size_t(y) * std::size_t(w);
    std::size_t nl = 0, nm = 0;
    if (albedo && albedo->image.channels() == 3) {  // the usual RGB albedo: a flat loop
      const float* a = albedo->image.pixel(0, y);
      for (int x = 0; x < w; ++x) {
        const float* p = a + std::size_t(x) * 3;
        const bool light = (p[0] > 1.0f) | (p[1] > 1.0f) | (p[2] > 1.0f);  // false for NaN
        f[x] = light ? SurfaceClasses::kLightInAlbedo : 0;
        nl += light;
      }
    } else if (albedo) {
      for (int x = 0; x < w; ++x)
        if (max3(albedo->image, x, y) > 1.0f) {
          f[x] |= SurfaceClasses::kLightInAlbedo;
          ++nl;
        }
    }
    if (out.colour_passes)
      for (int x = 0; x < w; ++x) {
        const float d = max3(diffuse->image, x, y), g = max3(glossy->image, x, y);
        if (d >= 0.0f && g > kMirrorGloss && g > kMirrorRatio * d) {
          f[x] |= SurfaceClasses::kMirror;
          ++nm;
        }
      }
    if (normal) {
      const Image& n = normal->image;
      const int nc = std::min(n.channels(), 3);
      std::size_t nb = 0;
      for (int x = 0; x < w; ++x) {
        const float* q = n.pixel(x, y);
        bool zero = nc > 0;
        for (int c = 0; c < nc; ++c) zero = zero && q[c] == 0.0f;  // false for NaN
        if (zero) {
          f[x] |= SurfaceClasses::kBackground;
          ++nb;
        }
      }
      background[std::size_t(y)] = nb;
    }
    light[std::size_t(y)] = nl;
    mirror[std::size_t(y)] = nm;
  });
  out.light_in_albedo = out.mirror = out.background = 0;
  for (std::size_t i = 0; i < light.size(); ++i) {
    out.light_in_albedo += light[i];
    out.mirror += mirror[i];
    out.background += background[i];
  }
}

void class_values(const SurfaceClasses& classes, std::uint8_t mask, float value, std::vector<float>& out) {
  out.resize(classes.flags.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = (classes.flags[i] & mask) ? value : 0.0f;
}

}  // namespace mcr
