// The soft-shadow generator against closed forms: an occluder plane parallel to the light
// gives s = d1/d2 - 1 on every occluded sample, and the converged unoccluded ground under the
// Gaussian light equals the integral of the shading computed here independently.
#include "soft_shadows.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mcr::lfgen {
namespace {

constexpr double kH = 4;  // the light's height over the ground

SoftShadowsSetup horizontal_light(const Camera& cam) {
  SoftShadowsSetup s;
  s.camera = cam;
  s.light_centre = {0, 0, kH};
  s.a1 = {1, 0, 0};
  s.a2 = {0, -1, 0};  // a1 x a2 = (0, 0, -1)
  s.half_side = 0.5;
  s.radiance = 2.0;
  return s;
}

Material grey() {
  Material m;
  m.albedo = {0.6, 0.6, 0.6};
  return m;
}

// An occluder half-plane x < 0 at height h over the ground, seen from under it (camera below
// h): its shadow's penumbra runs along x = 0.
TEST(LightFieldSoftShadows, ParallelOccluderPlaneGivesItsSlopeOnEverySample) {
  for (const double h : {0.5, 1.0, 2.0, 3.0}) {
    const Camera cam = Camera::look_at(24, 16, {0.0, -1.0, 0.3}, {0.0, 0.0, 0.0}, {0, 0, 1}, 20);
    SoftShadows gen(horizontal_light(cam));
    gen.scene().add_quad({-20, -20, 0}, {40, 0, 0}, {0, 40, 0}, grey());
    gen.scene().add_quad({-20, -20, h}, {20, 0, 0}, {0, 40, 0}, grey());
    gen.commit();
    const double expected = kH / (kH - h) - 1;  // d1 / d2 is the same on every shadow ray
    int shadowed = 0, mixed = 0;
    PixelSamples ps;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        ps.reset(16);
        gen.render_pixel(x, y, 4, 0.37, 0.61, ps);
        ASSERT_NEAR(ps.p.z, 0.0, 1e-5) << "every pixel sees the ground";
        int blocked = 0;
        for (const Vec3& v : ps.value) blocked += v.x == 0;
        if (blocked == 0) {
          EXPECT_EQ(ps.smin, 0.0);
          EXPECT_EQ(ps.smax, 0.0);
          continue;
        }
        ++shadowed;
        mixed += blocked < 16;
        EXPECT_NEAR(ps.smin, expected, 1e-4 * expected) << "h " << h << " pixel " << x << "," << y;
        EXPECT_NEAR(ps.smax, expected, 1e-4 * expected) << "h " << h << " pixel " << x << "," << y;
      }
    EXPECT_GT(shadowed, 20) << "h " << h;
    EXPECT_GT(mixed, 5) << "h " << h << ": no penumbra pixel";
  }
}

// The converged pixel: sum f I(y) / sum I(y) over the light, I Gaussian of sigma L/2, f the
// unoccluded diffuse shading albedo / pi * cos_r cos_l / r^2 * radiance of a ground point P
// (both cosines H / r): integrated by a fine midpoint rule here. The reference's one jitter per
// pixel makes it a shifted rectangle rule, first order in 1/l: 32x32 is within about 1e-3.
double analytic_ground(const Vec3& p, double albedo, double L, double radiance) {
  const int n = 1200;
  const double sigma = L / 2, step = 2 * L / n;
  double num = 0, den = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double yx = -L + (i + 0.5) * step, yy = -L + (j + 0.5) * step;
      const double w = std::exp(-(yx * yx + yy * yy) / (2 * sigma * sigma));
      const double dx = yx - p.x, dy = -yy - p.y;  // a2 = (0, -1, 0)
      const double r2 = dx * dx + dy * dy + kH * kH;
      num += w * albedo / M_PI * radiance * kH * kH / (r2 * r2);
      den += w;
    }
  return num / den;
}

TEST(LightFieldSoftShadows, ReferenceOfUnoccludedGroundIsTheGaussianIntegral) {
  const Camera cam = Camera::look_at(3, 3, {0.3, 0.2, 2.0}, {0.3, 0.2, 0.0}, {0, 1, 0}, 90);
  const SoftShadowsSetup setup = horizontal_light(cam);
  SoftShadows gen(setup);
  gen.scene().add_quad({-20, -20, 0}, {40, 0, 0}, {0, 40, 0}, grey());
  gen.commit();
  const std::vector<float> ref = render_reference(gen, 32, 7, 1);
  PixelSamples ps;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) {
      ps.reset(1);
      gen.render_pixel(x, y, 1, 0.5, 0.5, ps);  // the pixel's receiver
      const double want = analytic_ground(ps.p, 0.6, setup.half_side, setup.radiance);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(ref[3 * (y * 3 + x) + c], want, 1.5e-3 * want) << "pixel " << x << "," << y << " at " << ps.p.x << "," << ps.p.y;
    }
}

// The axes on a ground parallel to the light seen straight down: x_i = a_i, so e_i is a_i's
// image, focal_px / depth pixels per unit, along the screen's right / down.
TEST(LightFieldSoftShadows, AxesOfGroundUnderParallelLightAreTheLightAxesOnScreen) {
  const Camera cam = Camera::look_at(1, 1, {0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 90);
  SoftShadows gen(horizontal_light(cam));
  gen.scene().add_quad({-20, -20, 0}, {40, 0, 0}, {0, 40, 0}, grey());
  gen.commit();
  PixelSamples ps;
  ps.reset(1);
  gen.render_pixel(0, 0, 1, 0.5, 0.5, ps);
  const double k = cam.focal_px / 2;
  EXPECT_NEAR(ps.e1x, k * dot({1, 0, 0}, cam.right), 1e-3 * k);
  EXPECT_NEAR(ps.e1y, k * dot({1, 0, 0}, cam.down), 1e-3 * k);
  EXPECT_NEAR(ps.e2x, k * dot({0, -1, 0}, cam.right), 1e-3 * k);
  EXPECT_NEAR(ps.e2y, k * dot({0, -1, 0}, cam.down), 1e-3 * k);
  EXPECT_NEAR(ps.depth, 2.0, 1e-5);
}

}  // namespace
}  // namespace mcr::lfgen
