// The depth-of-field generator against the thin-lens circle of confusion: a plane facing the
// camera at depth z gives every sample s = -c, c the usual CoC formula per unit of lens radius.
#include "dof.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mcr::lfgen {
namespace {

// The textbook thin-lens blur: a point at distance z, lens focal length f focused at F with
// aperture diameter f / N, images as a disc of diameter D = (f / N) f |z - F| / (z (F - f)) on
// the sensor. Per unit of lens radius (our y), signed (positive behind the focus plane), in
// pixels: (D / 2) sign(z - F) / pitch.
double coc_px_per_lens_unit(double f_mm, double fstop, double focus_m, double z_m, double sensor_mm, int width) {
  const double f = f_mm / 1000, aperture = f / fstop;
  const double diameter = aperture * f * (z_m - focus_m) / (z_m * (focus_m - f));
  return diameter / 2 / (sensor_mm / 1000 / width);
}

TEST(LightFieldDof, PlaneAtDepthZHasTheThinLensCircleOfConfusion) {
  for (const double z : {0.9, 1.5, 2.0, 3.0, 8.0}) {
    DofSetup s;
    s.camera = Camera::look_at(16, 12, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}, 30);
    s.lens.lens_mm = 50;
    s.lens.fstop = 1.8;
    s.lens.focus_m = 2.0;
    Dof gen(s);
    Material m;
    gen.scene().add_quad({-50, z, -50}, {100, 0, 0}, {0, 0, 100}, m);  // camera depth z
    gen.commit();
    const double c = coc_px_per_lens_unit(50, 1.8, 2.0, z, 36, 16);
    PixelSamples ps;
    for (const auto& [x, y] : {std::pair{0, 0}, std::pair{7, 5}, std::pair{15, 11}}) {
      ps.reset(9);
      gen.render_pixel(x, y, 3, 0.2, 0.9, ps);
      EXPECT_NEAR(ps.smin, -c, 1e-4 * std::fabs(c) + 1e-6) << "z " << z << " pixel " << x << "," << y;
      EXPECT_NEAR(ps.smax, -c, 1e-4 * std::fabs(c) + 1e-6) << "z " << z << " pixel " << x << "," << y;
      EXPECT_EQ(ps.e1x, 1);
      EXPECT_EQ(ps.e1y, 0);
      EXPECT_EQ(ps.e2x, 0);
      EXPECT_EQ(ps.e2y, 1);
    }
  }
}

// The shift is real: the generator's ray through lens point u meets the plane at depth z at
// a point whose image through the lens centre lies c u pixels from the pixel, opposite in
// sign (so the pixel c u away sees that point through lens point 0: y = y' - (x - x') / s).
TEST(LightFieldDof, SampleThroughLensPointIsShiftedByTheSlope) {
  DofSetup s;
  s.camera = Camera::look_at(64, 64, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}, 30);
  s.lens.lens_mm = 85;
  s.lens.fstop = 1.4;
  s.lens.focus_m = 2.5;
  const Dof gen(s);
  const Camera& cam = gen.camera();
  for (const double z : {1.0, 6.0}) {
    const double c = s.lens.image_shift_px(z, 64);
    EXPECT_NEAR(c, coc_px_per_lens_unit(85, 1.4, 2.5, z, 36, 64), 1e-9 * std::fabs(c));
    const double px = 20.5, py = 40.5, u1 = 0.7, u2 = -0.4;
    Vec3 org, dir;
    gen.lens_ray(px, py, u1, u2, org, dir);
    const Vec3 q = org + dir * ((z - dot(org - cam.eye, cam.forward)) / dot(dir, cam.forward));
    double qx = 0, qy = 0;
    ASSERT_TRUE(cam.project(q, qx, qy));
    EXPECT_NEAR(px, qx + c * u1, 1e-6) << "z " << z;
    EXPECT_NEAR(py, qy + c * u2, 1e-6) << "z " << z;
  }
}

}  // namespace
}  // namespace mcr::lfgen
