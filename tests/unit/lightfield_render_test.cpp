// Rendering whole light fields: the same seed gives the same samples on any thread count,
// every pixel's samples sit on its l x l strata with one jitter, and the registry.
#include <gtest/gtest.h>

#include <cmath>

#include "expect_error.h"
#include "generator.h"

namespace mcr::lfgen {
namespace {

void expect_same(const LightField& a, const LightField& b) {
  ASSERT_EQ(a.samples(), b.samples());
  EXPECT_EQ(a.r, b.r);
  EXPECT_EQ(a.g, b.g);
  EXPECT_EQ(a.b, b.b);
  EXPECT_EQ(a.y1, b.y1);
  EXPECT_EQ(a.y2, b.y2);
  EXPECT_EQ(a.smin, b.smin);
  EXPECT_EQ(a.smax, b.smax);
  EXPECT_EQ(a.e1x, b.e1x);
  EXPECT_EQ(a.e2y, b.e2y);
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.px, b.px);
  EXPECT_EQ(a.nz, b.nz);
}

TEST(LightFieldRender, SameSeedSameSamplesOnAnyThreadCount) {
  for (const auto& name : scene_names()) {
    const auto gen = make_scene(name, 24, 20);
    const LightField one = render_lightfield(*gen, 3, 42, 1);
    const LightField two = render_lightfield(*gen, 3, 42, 2);
    SCOPED_TRACE(name);
    expect_same(one, two);
    const LightField other = render_lightfield(*gen, 3, 43, 2);
    EXPECT_NE(one.y1, other.y1) << "another seed, other jitters";
    EXPECT_EQ(render_reference(*gen, 4, 5, 1), render_reference(*gen, 4, 5, 2));
  }
}

TEST(LightFieldRender, SamplesSitOnThePixelsJitteredStrata) {
  for (const auto& name : {"soft_shadows", "dof"}) {
    const auto gen = make_scene(name, 12, 10);
    const int l = 4;
    const LightField lf = render_lightfield(*gen, l, 9, 0);
    EXPECT_EQ(lf.effect, gen->effect());
    EXPECT_EQ(lf.l, l);
    EXPECT_FLOAT_EQ(lf.y_range, float(gen->y_range()));
    EXPECT_FLOAT_EQ(lf.sigma_y, float(gen->y_range() / 2));
    const double L = gen->y_range(), cell = 2 * L / l;
    for (std::size_t p = 0; p < lf.pixels(); ++p) {
      // The jitter is the first sample's offset within its cell; every sample shares it.
      const double j1 = (lf.y1[p * l * l] + L) / cell, j2 = (lf.y2[p * l * l] + L) / cell;
      ASSERT_GE(j1, 0);
      ASSERT_LT(j1, 1);
      for (int j = 0; j < l; ++j)
        for (int i = 0; i < l; ++i) {
          const std::size_t k = p * l * l + std::size_t(i + l * j);
          EXPECT_NEAR(lf.y1[k], -L + (i + j1) * cell, 1e-5) << name << " pixel " << p;
          EXPECT_NEAR(lf.y2[k], -L + (j + j2) * cell, 1e-5) << name << " pixel " << p;
        }
      EXPECT_LE(lf.smin[p], lf.smax[p]);
      EXPECT_NEAR(std::hypot(lf.nx[p], lf.ny[p], lf.nz[p]), 1.0, 1e-5);
    }
  }
}

TEST(LightFieldRender, GiKeepsItsVPlaneRange) {
  const auto gen = make_scene("gi", 8, 8);
  const LightField lf = render_lightfield(*gen, 4, 3, 1);
  EXPECT_EQ(lf.effect, LightFieldEffect::Gi);
  EXPECT_FLOAT_EQ(lf.y_range, 5.f);
  EXPECT_FLOAT_EQ(lf.sigma_y, float(2 / 2.8));
  for (std::size_t k = 0; k < lf.samples(); ++k) {
    ASSERT_LE(std::fabs(lf.y1[k]), 5.f);
    ASSERT_LE(std::fabs(lf.y2[k]), 5.f);
  }
  for (std::size_t p = 0; p < lf.pixels(); ++p) EXPECT_GT(lf.smax[p], 0) << "a closed room: a reflector in every pixel";
}

TEST(LightFieldRender, RegistryNamesItsScenes) {
  EXPECT_EQ(scene_names(), (std::vector<std::string>{"soft_shadows", "dof", "gi", "soft_shadows_dof"}));
  testutil::expect_error(Errc::InvalidArgument, {"'shadows'", "soft_shadows, dof, gi, soft_shadows_dof"}, [] { make_scene("shadows", 8, 8); });
  testutil::expect_error(Errc::InvalidArgument, {"0x8"}, [] { make_scene("dof", 0, 8); });
  testutil::expect_error(Errc::InvalidArgument, {"l = 65"}, [] {
    const auto gen = make_scene("dof", 2, 2);
    render_lightfield(*gen, 65, 1);
  });
}

}  // namespace
}  // namespace mcr::lfgen
