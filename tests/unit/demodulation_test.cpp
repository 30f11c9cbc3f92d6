// The demodulation rule (prepare/demodulation.h) on one row, per instruction set: the
// divisor against the rule written out here, the illumination finite for every finite
// colour (up to +-FLT_MAX over a dark albedo), and divisor x illumination the colour again.
#include "prepare/demodulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "util/isa.h"

namespace mcr {
namespace {

// The rule, independently: albedo floored and capped at 1 (1 when not finite), then at
// least |c| / 2^126 for a finite colour.
float expected_divisor(float albedo, float colour, float floor) {
  double a = std::isfinite(albedo) ? std::min(std::max(double(albedo), double(floor)), 1.0) : 1.0;
  if (std::isfinite(colour)) a = std::max(a, std::fabs(double(colour)) / std::ldexp(1.0, 126));
  return float(a);
}

TEST(Demodulation, RowFollowsTheRuleOnEveryInstructionSet) {
  const float big = std::numeric_limits<float>::max(), inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> colours = {0.5f, -2.0f, big, -big, 1e38f, 8.5e37f, 1e30f, 1e-30f, 0.0f, inf, -inf, nan};
  const std::vector<float> albedos = {0.3f, 0.0f, 1.0f, 200.0f, 1e-7f, nan, inf};
  // Every pairing, in rows long enough for the 8-wide path and its scalar tail.
  std::vector<float> co, ad;
  for (float c : colours)
    for (float a : albedos) {
      co.push_back(c);
      ad.push_back(a);
    }
  while (co.size() % 3) {
    co.push_back(1.0f);
    ad.push_back(1.0f);
  }
  const int n = int(co.size() / 3);
  const float floor = 0.01f;
  for (Isa level : {Isa::Generic, best_isa()}) {
    const ScopedIsa use(level);
    SCOPED_TRACE(isa_name(level));
    std::vector<float> al(co.size()), il(co.size());
    demodulate_row(ad.data(), 3, co.data(), n, floor, al.data(), il.data());
    for (std::size_t i = 0; i < co.size(); ++i) {
      SCOPED_TRACE("colour " + std::to_string(co[i]) + " albedo " + std::to_string(ad[i]));
      ASSERT_EQ(al[i], expected_divisor(ad[i], co[i], floor));
      if (std::isnan(co[i])) {
        EXPECT_TRUE(std::isnan(il[i]));
        continue;
      }
      if (std::isinf(co[i])) {
        EXPECT_EQ(il[i], co[i]);  // non-finite colour is the filter's policy, unchanged here
        continue;
      }
      ASSERT_TRUE(std::isfinite(il[i]));
      EXPECT_EQ(il[i], co[i] / al[i]);
      EXPECT_NEAR(double(il[i]) * double(al[i]), double(co[i]), 1e-6 * std::fabs(double(co[i])));
    }
  }
}

TEST(Demodulation, OrdinaryValuesAreDividedByTheFlooredAlbedo) {
  // Below |colour| = 2^126 x albedo the second line of the rule never acts.
  const float co[6] = {1e6f, 0.25f, -3.0f, 1e30f, 2.0f, 0.0f};
  const float ad[6] = {0.5f, 0.001f, 0.9f, 0.2f, 0.0f, 0.75f};
  float al[6], il[6];
  demodulate_row(ad, 3, co, 2, 0.01f, al, il);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(al[i], std::max(ad[i], 0.01f));
    EXPECT_EQ(il[i], co[i] / std::max(ad[i], 0.01f));
  }
}

TEST(Demodulation, AnAlbedoThatHoldsLightDoesNotDriveTheIllumination) {
  // A mirror under a sun at 1 spp: the albedo flips between 200 (the sample's bounce hit
  // the sun) and 0.4 from pixel to pixel, with the colour 120 and 0.2. Divided by the raw
  // albedo the illumination would be 0.6 and 0.5 here but 300 where a bright colour meets
  // a dark albedo; capped at 1 the excess stays in the colour, and every illumination is
  // within [colour, colour / floor], so remodulation never multiplies a pixel's light by a
  // neighbour's 200.
  for (Isa level : {Isa::Generic, best_isa()}) {
    const ScopedIsa use(level);
    SCOPED_TRACE(isa_name(level));
    std::vector<float> ad, co;
    for (int i = 0; i < 16; ++i) {
      const bool hit = i % 2 == 0;
      for (int c = 0; c < 3; ++c) {
        ad.push_back(hit ? 200.0f : 0.4f);
        co.push_back(hit ? 120.0f : (i % 4 == 1 ? 0.2f : 120.0f));
      }
    }
    const int n = int(co.size() / 3);
    std::vector<float> al(co.size()), il(co.size());
    demodulate_row(ad.data(), 3, co.data(), n, 0.01f, al.data(), il.data());
    for (std::size_t i = 0; i < co.size(); ++i) {
      EXPECT_LE(al[i], 1.0f);
      EXPECT_EQ(al[i], ad[i] > 1.0f ? 1.0f : ad[i]);
      EXPECT_EQ(il[i], co[i] / al[i]);
      // The largest divided value over the row is the brightest colour over the smallest
      // divisor, never more: remodulating any pixel's illumination by any divisor of the
      // row gives at most max colour / min divisor (300), not 200 x 300.
      for (std::size_t j = 0; j < co.size(); ++j) EXPECT_LE(double(il[i]) * al[j], 120.0 / 0.4 + 1e-3);
    }
  }
}

}  // namespace
}  // namespace mcr
