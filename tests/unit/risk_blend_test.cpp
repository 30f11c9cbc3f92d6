// The risk blend (kernels/risk_blend.h) against its closed form: a window whose result is off
// the input by b everywhere, with input variance v, takes a = v / b^2 of the result (b^2 > v)
// or keeps it whole (b^2 <= v); windows are clipped to the region; pixels of unknown or
// non-finite variance take no part and keep the result.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "kernels/risk_blend.h"

namespace mcr {
namespace {

Image filled(int w, int h, float v) { return Image(w, h, 3, v); }

TEST(RiskBlend, AnOffsetLargerThanTheNoiseIsScaledByVarianceOverItsSquare) {
  for (const double b2_over_v : {4.0, 16.0, 0.5}) {
    SCOPED_TRACE(b2_over_v);
    const double v = 0.01, b = std::sqrt(b2_over_v * v);
    const Image y = filled(12, 10, 1.0f), var = filled(12, 10, float(v));
    Image out = filled(12, 10, float(1.0 + b));
    const double mean_a = blend_by_risk(y, var, Roi{0, 0, 12, 10}, 3, 2, out);
    const double a = std::min(1.0, 1.0 / b2_over_v);
    EXPECT_NEAR(mean_a, a, 1e-6);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.at(5, 5, c), 1.0 + a * b, 1e-5);
  }
}

TEST(RiskBlend, ABandOfBiasIsWeighedOverEachWindow) {
  // Result off by b = 0.4 in columns 10-11 only, elsewhere equal to the input; variance 0.01.
  // Pixel (x, 5), radius 2: the window holds 5 rows of the band columns it covers, each term
  // weighted by 1 / (f^2 + 0.01) with f the result there.
  const int W = 24, H = 12;
  const double v = 0.01, b = 0.4;
  const Image y = filled(W, H, 1.0f), var = filled(W, H, float(v));
  Image out = filled(W, H, 1.0f);
  for (int yy = 0; yy < H; ++yy)
    for (int c = 0; c < 3; ++c) out.at(10, yy, c) = out.at(11, yy, c) = float(1.0 + b);
  Image got = out;
  blend_by_risk(y, var, Roi{0, 0, W, H}, 2, 1, got);
  const double wb = 1.0 / ((1 + b) * (1 + b) + 0.01), w1 = 1.0 / (1.0 + 0.01);
  for (int x = 6; x <= 15; ++x) {
    int band = 0;
    for (int q = x - 2; q <= x + 2; ++q) band += q == 10 || q == 11;
    const double sv = 5 * (band * wb + (5 - band) * w1) * v, sd = 5 * band * wb * b * b;
    const double a = sd > sv ? sv / sd : 1.0;
    const double want = 1.0 + a * (double(out.at(x, 5, 0)) - 1.0);
    EXPECT_NEAR(got.at(x, 5, 0), want, 1e-5) << "x " << x;
  }
  EXPECT_LT(got.at(10, 5, 0), 1.0 + 0.3 * b) << "two biased columns in a 5-wide window: mostly the input";
}

TEST(RiskBlend, OnlyTheRegionIsReadAndChanged) {
  const int W = 16, H = 16;
  const Image y = filled(W, H, 1.0f), var = filled(W, H, 0.01f);
  Image out = filled(W, H, 1.5f);
  for (int yy = 0; yy < H; ++yy)  // outside the region: a result equal to the input
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, yy, c) = 1.0f;
  Image got = out;
  blend_by_risk(y, var, Roi{4, 0, W, H}, 3, 2, got);
  // Inside, every window sees only the offset 0.5 (the equal pixels outside are not read):
  // a = 0.01 / 0.25 = 0.04 everywhere, at the region's edge too.
  for (int yy = 0; yy < H; ++yy) {
    for (int x = 0; x < 4; ++x) EXPECT_EQ(got.at(x, yy, 0), 1.0f);
    for (int x = 4; x < W; ++x) EXPECT_NEAR(got.at(x, yy, 0), 1.0 + 0.04 * 0.5, 1e-5) << x << "," << yy;
  }
}

TEST(RiskBlend, UnknownVarianceAndNonFinitePixelsKeepTheResult) {
  const int W = 8, H = 8;
  const Image y = filled(W, H, 1.0f);
  Image var = filled(W, H, -1.0f);  // unknown everywhere: nothing to weigh
  Image out = filled(W, H, 3.0f);
  Image got = out;
  EXPECT_EQ(blend_by_risk(y, var, Roi{0, 0, W, H}, 2, 1, got), 1.0);
  EXPECT_EQ(got.storage(), out.storage());
  // Known variance, one pixel's input NaN: it keeps its result and its neighbours are blended
  // as if it were not there (no NaN spreads).
  var = filled(W, H, 0.01f);
  Image yn = y;
  yn.at(3, 3, 1) = std::numeric_limits<float>::quiet_NaN();
  got = out;
  blend_by_risk(yn, var, Roi{0, 0, W, H}, 2, 1, got);
  EXPECT_EQ(got.at(3, 3, 0), 3.0f);
  for (float v : got.storage()) EXPECT_TRUE(std::isfinite(v));
  EXPECT_NEAR(got.at(4, 4, 0), 1.0 + 0.01 / 4.0 * 2.0, 1e-5);
}

}  // namespace
}  // namespace mcr
