// The indirect-light generator: the v-plane sampler's weights gamma / pdf / C average to 1
// (so for a constant L_in the plain mean is L_in), C is the integral of gamma, and a parallel
// reflector at height z gives s = z on every sample.
#include "gi.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mcr::lfgen {
namespace {

TEST(LightFieldGi, GammaIntegralMatchesQuadrature) {
  const int n = 4000;
  const double a = kVRange, h = 2 * a / n;
  double sum = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) sum += v_gamma(-a + (i + 0.5) * h, -a + (j + 0.5) * h);
  EXPECT_NEAR(v_gamma_integral(a), sum * h * h, 1e-5);
  EXPECT_NEAR(v_gamma_integral(1e4), M_PI, 1e-3);  // the whole plane: the cosine-weighted hemisphere
}

TEST(LightFieldGi, SamplerWeightsAverageToOne) {
  for (const int l : {64, 256}) {
    double sum = 0, vmax = 0;
    for (int j = 0; j < l; ++j)
      for (int i = 0; i < l; ++i) {
        double v1 = 0, v2 = 0, w = 0;
        v_plane_sample((i + 0.31) / l, (j + 0.77) / l, v1, v2, w);
        ASSERT_GT(w, 0);
        sum += w;
        vmax = std::max({vmax, std::fabs(v1), std::fabs(v2)});
      }
    EXPECT_NEAR(sum / (double(l) * l), 1.0, l == 64 ? 2e-3 : 2e-4) << "l " << l;
    EXPECT_LE(vmax, kVRange);
    EXPECT_GT(vmax, 0.9 * kVRange);
  }
}

// Receiver: a floor at z = 0; reflector: a ceiling at height z, wide enough for |v| <= 5.
TEST(LightFieldGi, ParallelReflectorGivesItsDistanceAsSlope) {
  for (const double z : {0.5, 1.5}) {
    GiSetup s;
    s.camera = Camera::look_at(8, 8, {0, -0.3, 0.2}, {0, 0.5, 0}, {0, 0, 1}, 20);  // sees only the floor
    s.light_pos = {0, 0, 0.5 * z};
    s.intensity = 1;
    Gi gen(s);
    Material m;
    gen.scene().add_quad({-50, -50, 0}, {100, 0, 0}, {0, 100, 0}, m);
    gen.scene().add_quad({-50, -50, z}, {100, 0, 0}, {0, 100, 0}, m);
    gen.commit();
    PixelSamples ps;
    for (int y = 0; y < 8; y += 3)
      for (int x = 0; x < 8; x += 3) {
        ps.reset(16);
        gen.render_pixel(x, y, 4, 0.5, 0.25, ps);
        ASSERT_NEAR(ps.p.z, 0.0, 1e-5);
        EXPECT_NEAR(ps.smin, z, 1e-4 * z);
        EXPECT_NEAR(ps.smax, z, 1e-4 * z);
        for (std::size_t k = 0; k < 16; ++k) EXPECT_GT(ps.value[k].x, 0) << "the lit ceiling is seen";
      }
  }
}

}  // namespace
}  // namespace mcr::lfgen
