// prepare/first_hit.h: the pixels whose first sample met no surface (Blender's Depth 1e10,
// Position 0) though the pixel's averaged normal shows others did take their neighbours' position
// and depth, against the closed form of the nearest ring's mean; the sky and a non-finite depth
// are left alone; and what it is for: a filter reading position smooths fog it did not.
#include "prepare/first_hit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "feature_filter_testutil.h"
#include "pipeline/reconstruction.h"

namespace mcr {
namespace {

// A plane seen through fog: position (x/10, y/10, 5), depth 5, and at the pixels `missed` says
// the first sample scattered in the air (position 0, depth 1e10; the averaged normal 0.9 long,
// as everywhere). A second, averaged depth (Blender's Denoising Depth) is finite everywhere.
Frame fog_frame(int w, int h, double missed, unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution miss(missed);
  std::normal_distribution<float> noise(0.0f, 0.1f);
  Image colour(w, h, 3), position(w, h, 3), depth(w, h, 1), averaged(w, h, 1), normal(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool m = miss(rng);
      for (int c = 0; c < 3; ++c) colour.at(x, y, c) = 0.5f + noise(rng);
      position.at(x, y, 0) = m ? 0.0f : float(x) * 0.1f;
      position.at(x, y, 1) = m ? 0.0f : float(y) * 0.1f;
      position.at(x, y, 2) = m ? 0.0f : 5.0f;
      depth.at(x, y, 0) = m ? 1e10f : 5.0f;
      averaged.at(x, y, 0) = 3.0f;
      normal.at(x, y, 2) = 0.9f;
    }
  Frame f = testutil::colour_frame(colour);
  testutil::add_pass(f, Role::Position, position);
  f.passes.push_back(testutil::named_pass(Role::Depth, "Depth", depth));
  f.passes.push_back(testutil::named_pass(Role::Depth, "Denoising Depth", averaged));
  testutil::add_pass(f, Role::Normal, normal);
  return f;
}

TEST(FirstHit, HolesTakeTheMeanOfTheNearestRingThatMetASurface) {
  Frame f = fog_frame(9, 9, 0.0, 1);
  Image& pos = testutil::pass_image(f, Role::Position);
  Image& depth = f.passes[2].image;
  // (4, 4) missed, and so did its whole first ring but (5, 3): that pixel alone is the mean.
  for (int y = 3; y <= 5; ++y)
    for (int x = 3; x <= 5; ++x)
      if (!(x == 5 && y == 3)) {
        depth.at(x, y, 0) = 1e10f;
        for (int c = 0; c < 3; ++c) pos.at(x, y, c) = 0.0f;
      }
  // (0, 8) missed with no ring but the second one's pixels: a corner, the ring clipped.
  depth.at(0, 8, 0) = 1e10f;
  depth.at(1, 8, 0) = depth.at(0, 7, 0) = depth.at(1, 7, 0) = 1e10f;
  // The sky: no sample met anything (normal 0) at (8, 0); a non-finite depth at (8, 8).
  depth.at(8, 0, 0) = 1e10f;
  testutil::pass_image(f, Role::Normal).at(8, 0, 2) = 0.0f;
  depth.at(8, 8, 0) = testutil::kNaN;
  const Frame before = f;

  const FirstHitMap map = first_hit_map(f, Roi::all(9, 9), 2);
  ASSERT_EQ(map.state.size(), 81u);
  EXPECT_EQ(fill_first_hit_holes(f, map, 2), 8u + 4u);
  EXPECT_FLOAT_EQ(pos.at(4, 4, 0), 0.5f);  // (5, 3)'s
  EXPECT_FLOAT_EQ(pos.at(4, 4, 1), 0.3f);
  EXPECT_FLOAT_EQ(depth.at(4, 4, 0), 5.0f);
  // (3, 3): its ring at 1 holds (2, 2), (3, 2), (4, 2), (2, 3), (2, 4).
  EXPECT_NEAR(pos.at(3, 3, 0), (0.2f + 0.3f + 0.4f + 0.2f + 0.2f) / 5.0f, 1e-6);
  // (0, 8): its ring at 1 is all missed; at 2 it holds (2, 6), (2, 7), (2, 8), (0, 6), (1, 6).
  EXPECT_NEAR(pos.at(0, 8, 0), (0.2f + 0.2f + 0.2f + 0.0f + 0.1f) / 5.0f, 1e-6);
  EXPECT_NEAR(pos.at(0, 8, 1), (0.6f + 0.7f + 0.8f + 0.6f + 0.6f) / 5.0f, 1e-6);
  // Left alone: the sky, the non-finite depth, the averaged depth, every pixel that met a surface.
  EXPECT_EQ(depth.at(8, 0, 0), 1e10f);
  EXPECT_TRUE(std::isnan(depth.at(8, 8, 0)));
  EXPECT_EQ(f.passes[3].image.storage(), before.passes[3].image.storage());
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x)
      if (map.state[std::size_t(y) * 9 + std::size_t(x)] != kFirstHitHole)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(pos.at(x, y, c), before.image(Role::Position).at(x, y, c));
}

double mse_to(const Image& out, float value) {
  double e = 0.0;
  for (std::size_t i = 0; i < out.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) e += std::pow(double(out.data()[i * 3 + std::size_t(c)]) - value, 2);
  return e / double(out.pixel_count() * 3);
}

// A third of the pixels' first samples scattered in the fog: read as geometry, those pixels are
// edges to all their neighbours and keep their noise. Filled, the plane is one surface again. The
// same frame with those pixels' normal 0 (as if nothing were there: not filled) is the check.
// (pwaf sizes its windows by the noise and lost less to the holes, 0.70x here: not asserted.)
TEST(FirstHit, AFilterReadingPositionSmoothsTheFogItsFirstSamplesMissed) {
  const Frame f = fog_frame(48, 40, 0.3, 2);
  Frame unfilled = f;
  Image& n = testutil::pass_image(unfilled, Role::Normal);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 48; ++x)
      if (f.passes[2].image.at(x, y, 0) > 1e9f) n.at(x, y, 2) = 0.0f;
  for (const char* name : {"bilateral", "atrous"}) {
    SCOPED_TRACE(name);
    const auto filter = make_committed_filter(name, {{"step_back", "off"}});
    const double filled = mse_to(filter->execute(f), 0.5f);
    bool said = false;
    for (const std::string& note : filter->notes()) said = said || note.find("first sample met no surface") != std::string::npos;
    EXPECT_TRUE(said);
    const double kept = mse_to(filter->execute(unfilled), 0.5f);
    EXPECT_LT(filled, 0.7 * kept) << "unfilled " << kept;
  }
}

}  // namespace
}  // namespace mcr
