// Metrics against closed forms and a plain brute-force SSIM.
#include "metrics/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "expect_error.h"
#include "metrics_oracle.h"
#include "util/error.h"

namespace mcr {
namespace {

using namespace testutil;

Image constant_image(int w, int h, float r, float g, float b, int channels = 3) {
  Image im(w, h, channels, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      im.at(x, y, 0) = r;
      im.at(x, y, 1) = g;
      im.at(x, y, 2) = b;
    }
  return im;
}

Image random_image(int w, int h, unsigned seed, float lo = 0.0f, float hi = 1.0f,
                   int channels = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(lo, hi);
  Image im(w, h, channels);
  for (float& v : im.storage()) v = dist(rng);
  return im;
}

// ---- Tests ----

TEST(MetricsTest, IdenticalImagesGiveZeroErrorInfinitePsnrUnitSsim) {
  const Image a = random_image(37, 23, 1, -0.5f, 2.0f);
  const ImageMetrics m = compare_images(a, a);
  EXPECT_EQ(m.rmse, 0.0);
  EXPECT_EQ(m.relmse, 0.0);
  EXPECT_TRUE(std::isinf(m.psnr) && m.psnr > 0);
  EXPECT_NEAR(m.ssim, 1.0, 1e-12);
  EXPECT_EQ(rmse(a, a), 0.0);
  EXPECT_EQ(relmse(a, a), 0.0);
  EXPECT_TRUE(std::isinf(psnr(a, a)));
  EXPECT_NEAR(ssim(a, a), 1.0, 1e-12);
}

TEST(MetricsTest, ConstantOffsetMatchesClosedForms) {
  // r = 0.25, x = r + d with d = 0.5: both inside [0,1], so clamping changes nothing.
  const double r = 0.25, d = 0.5;
  const Image ref = constant_image(19, 11, float(r), float(r), float(r));
  const Image img = constant_image(19, 11, float(r + d), float(r + d), float(r + d));
  const ImageMetrics m = compare_images(ref, img);
  EXPECT_NEAR(m.rmse, d, 1e-12);
  EXPECT_NEAR(m.relmse, d * d / (r * r + 0.01), 1e-12);
  EXPECT_NEAR(m.psnr, -10.0 * std::log10(d * d), 1e-9);
  EXPECT_NEAR(rmse(ref, img), d, 1e-12);
  EXPECT_NEAR(relmse(ref, img), d * d / (r * r + 0.01), 1e-12);
  EXPECT_NEAR(psnr(ref, img), -10.0 * std::log10(d * d), 1e-9);
}

TEST(MetricsTest, RelmseUsesReferenceInDenominatorPerChannel) {
  const Image ref = constant_image(4, 4, 0.0f, 1.0f, 2.0f);
  const Image img = constant_image(4, 4, 0.1f, 1.2f, 1.0f);
  const double expected =
      (0.01 / 0.01 + 0.04 / 1.01 + 1.0 / 4.01) / 3.0;
  EXPECT_NEAR(relmse(ref, img), expected, 1e-6);  // float inputs: ~1e-7 relative
}

TEST(MetricsTest, AlphaMseIsTheMeanSquareOfTheFirstChannelsDifference) {
  Image r(2, 2, 1), a(2, 2, 2);
  const float rv[4] = {0.0f, 1.0f, 0.5f, 0.25f}, av[4] = {0.5f, 1.0f, 0.0f, std::numeric_limits<float>::quiet_NaN()};
  for (int i = 0; i < 4; ++i) {
    r.data()[i] = rv[i];
    a.data()[2 * i] = av[i];
    a.data()[2 * i + 1] = 7.0f;  // not the alpha
  }
  // (0.5^2 + 0 + 0.5^2 + 0.25^2 (NaN read as 0)) / 4
  EXPECT_DOUBLE_EQ(alpha_mse(r, a), (0.25 + 0.25 + 0.0625) / 4.0);
  EXPECT_DOUBLE_EQ(alpha_mse(a, a), 0.0);
  expect_error(Errc::SizeMismatch, {"alpha_mse", "2x2", "3x2"}, [&] { alpha_mse(r, Image(3, 2, 1)); });
}

TEST(MetricsTest, SsimOfTwoConstantImagesMatchesClosedForm) {
  const double a = 0.2, b = 0.7;
  const Image x = constant_image(13, 9, float(a), float(a), float(a));
  const Image y = constant_image(13, 9, float(b), float(b), float(b));
  const double fa = float(a), fb = float(b);
  const double expected = (2 * fa * fb + kC1) / (fa * fa + fb * fb + kC1);
  EXPECT_NEAR(ssim(x, y), expected, 1e-12);
  EXPECT_NEAR(compare_images(x, y).ssim, expected, 1e-12);
}

TEST(MetricsTest, SsimIsSymmetric) {
  const Image a = random_image(31, 17, 2);
  const Image b = random_image(31, 17, 3);
  EXPECT_DOUBLE_EQ(ssim(a, b), ssim(b, a));
}

TEST(MetricsTest, SsimOfDifferentRandomImageIsBelowOne) {
  const Image a = random_image(32, 32, 4);
  const Image b = random_image(32, 32, 5);
  const double s = ssim(a, b);
  EXPECT_LT(s, 0.5);
  EXPECT_GT(s, -1.0);
  // A slightly perturbed copy is close to, but below, 1.
  Image c = a;
  c.at(10, 10, 1) += 0.3f;
  EXPECT_LT(ssim(a, c), 1.0);
  EXPECT_GT(ssim(a, c), 0.95);
}

TEST(MetricsTest, ValuesAboveOneActAsOneInPsnrAndSsimButNotInRmse) {
  const Image ref = constant_image(8, 8, 1.0f, 1.0f, 1.0f);
  const Image img = constant_image(8, 8, 3.0f, 1.5f, 2.0f);
  EXPECT_TRUE(std::isinf(psnr(ref, img)));
  EXPECT_NEAR(ssim(ref, img), 1.0, 1e-12);
  EXPECT_NEAR(rmse(ref, img), std::sqrt((4.0 + 0.25 + 1.0) / 3.0), 1e-12);

  // 0.5 vs 1.5: clamped difference 0.5 in PSNR, full difference 1.0 in RMSE.
  const Image half = constant_image(8, 8, 0.5f, 0.5f, 0.5f);
  const Image high = constant_image(8, 8, 1.5f, 1.5f, 1.5f);
  EXPECT_NEAR(psnr(half, high), -10.0 * std::log10(0.25), 1e-9);
  EXPECT_NEAR(rmse(half, high), 1.0, 1e-12);
  // Negative values clamp to 0.
  const Image zero = constant_image(8, 8, 0.0f, 0.0f, 0.0f);
  const Image neg = constant_image(8, 8, -2.0f, -2.0f, -2.0f);
  EXPECT_TRUE(std::isinf(psnr(zero, neg)));
  EXPECT_NEAR(ssim(zero, neg), 1.0, 1e-12);
}

class SsimBruteForceTest : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(SsimBruteForceTest, SeparableSsimMatchesBruteForce2D) {
  const auto [w, h] = GetParam();
  // Range beyond [0,1] so that clamping is exercised too.
  const Image a = random_image(w, h, 10u + w * 31u + h, -0.2f, 1.2f);
  Image b = random_image(w, h, 20u + w * 17u + h, -0.2f, 1.2f);
  // Make b correlated with a so the covariance term matters.
  for (std::size_t i = 0; i < b.storage().size(); ++i)
    b.storage()[i] = 0.6f * a.storage()[i] + 0.4f * b.storage()[i];
  const double expected = brute_force_ssim(a, b);
  EXPECT_NEAR(ssim(a, b), expected, 1e-9) << w << "x" << h;
  EXPECT_NEAR(ssim(a, b, 1), expected, 1e-9) << w << "x" << h;
}

INSTANTIATE_TEST_SUITE_P(Sizes, SsimBruteForceTest,
                         ::testing::Values(std::make_pair(1, 1), std::make_pair(1, 7),
                                           std::make_pair(7, 1), std::make_pair(5, 3),
                                           std::make_pair(2, 2), std::make_pair(16, 16),
                                           std::make_pair(23, 40), std::make_pair(9, 150),
                                           std::make_pair(70, 5)),
                         [](const auto& info) {
                           return std::to_string(info.param.first) + "x" +
                                  std::to_string(info.param.second);
                         });

TEST(MetricsTest, ResultsAreBitwiseIdenticalForAnyThreadCount) {
  const Image a = random_image(97, 203, 6, -0.1f, 1.5f);
  const Image b = random_image(97, 203, 7, -0.1f, 1.5f);
  const ImageMetrics m1 = compare_images(a, b, 1);
  const double t1 = temporal_error(a, b, 1);
  for (int n : {2, 3, 8}) {
    const ImageMetrics m = compare_images(a, b, n);
    EXPECT_EQ(m.rmse, m1.rmse) << n << " threads";
    EXPECT_EQ(m.relmse, m1.relmse) << n << " threads";
    EXPECT_EQ(m.psnr, m1.psnr) << n << " threads";
    EXPECT_EQ(m.ssim, m1.ssim) << n << " threads";
    EXPECT_EQ(rmse(a, b, n), m1.rmse);
    EXPECT_EQ(relmse(a, b, n), m1.relmse);
    EXPECT_EQ(psnr(a, b, n), m1.psnr);
    EXPECT_EQ(ssim(a, b, n), m1.ssim);
    EXPECT_EQ(temporal_error(a, b, n), t1) << n << " threads";
  }
  EXPECT_EQ(compare_images(a, b, 0).ssim, m1.ssim);
}

TEST(MetricsTest, TemporalErrorIsMeanAbsoluteLuminanceChange) {
  const Image prev = constant_image(10, 6, 0.1f, 0.2f, 0.3f);
  const Image cur = constant_image(10, 6, 0.5f, 0.1f, 0.9f);
  auto lum = [](double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; };
  const double dy = std::abs(lum(0.5f, 0.1f, 0.9f) - lum(0.1f, 0.2f, 0.3f));
  EXPECT_NEAR(temporal_error(prev, cur), dy, 1e-12);
  EXPECT_NEAR(temporal_error(cur, prev), dy, 1e-12);
  EXPECT_EQ(temporal_error(prev, prev), 0.0);

  // Only the left half changes: half the mean. A chroma change at equal luminance counts 0.
  Image half = prev;
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 5; ++x) {
      half.at(x, y, 0) = 0.5f;
      half.at(x, y, 1) = 0.1f;
      half.at(x, y, 2) = 0.9f;
    }
  EXPECT_NEAR(temporal_error(prev, half), dy / 2, 1e-12);
  const Image red = constant_image(3, 3, 1.0f, 0.0f, 0.0f);
  const Image grey = constant_image(3, 3, 0.2126f, 0.2126f, 0.2126f);
  EXPECT_NEAR(temporal_error(red, grey), 0.0, 1e-7);
}

TEST(MetricsTest, NonFiniteValuesAreReadAsZero) {
  Image a = random_image(20, 20, 8);
  const Image b = random_image(20, 20, 9);
  Image a_zeroed = a;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  a.at(3, 4, 0) = nan;
  a.at(7, 1, 1) = inf;
  a.at(0, 19, 2) = -inf;
  a_zeroed.at(3, 4, 0) = 0.0f;
  a_zeroed.at(7, 1, 1) = 0.0f;
  a_zeroed.at(0, 19, 2) = 0.0f;

  auto expect_same = [](const Image& x, const Image& y, const Image& zx, const Image& zy) {
    const ImageMetrics m = compare_images(x, y);
    const ImageMetrics z = compare_images(zx, zy);
    EXPECT_TRUE(std::isfinite(m.rmse) && std::isfinite(m.relmse) && std::isfinite(m.psnr) &&
                std::isfinite(m.ssim));
    EXPECT_EQ(m.rmse, z.rmse);
    EXPECT_EQ(m.relmse, z.relmse);
    EXPECT_EQ(m.psnr, z.psnr);
    EXPECT_EQ(m.ssim, z.ssim);
    EXPECT_EQ(temporal_error(x, y), temporal_error(zx, zy));
  };
  expect_same(a, b, a_zeroed, b);  // non-finite values in the reference
  expect_same(b, a, b, a_zeroed);  // and in the image
  // A NaN against a 0 is no error at all.
  const Image zero = constant_image(4, 4, 0.0f, 0.0f, 0.0f);
  const Image nans = constant_image(4, 4, nan, inf, -inf);
  EXPECT_EQ(rmse(zero, nans), 0.0);
  EXPECT_EQ(temporal_error(zero, nans), 0.0);
  EXPECT_NEAR(ssim(zero, nans), 1.0, 1e-12);
}

TEST(MetricsTest, ExtraChannelsAreIgnored) {
  const Image a3 = random_image(12, 12, 11);
  const Image b3 = random_image(12, 12, 12);
  Image a4(12, 12, 4, 0.0f), b5(12, 12, 5, 7.0f);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 12; ++x)
      for (int c = 0; c < 3; ++c) {
        a4.at(x, y, c) = a3.at(x, y, c);
        b5.at(x, y, c) = b3.at(x, y, c);
      }
  a4.at(5, 5, 3) = 100.0f;
  const ImageMetrics m3 = compare_images(a3, b3), m45 = compare_images(a4, b5);
  EXPECT_EQ(m3.rmse, m45.rmse);
  EXPECT_EQ(m3.relmse, m45.relmse);
  EXPECT_EQ(m3.psnr, m45.psnr);
  EXPECT_EQ(m3.ssim, m45.ssim);
  EXPECT_EQ(temporal_error(a3, b3), temporal_error(a4, b5));
}

TEST(MetricsTest, SizeMismatchThrowsNamingBothSizes) {
  const Image a(64, 48, 3), b(32, 32, 3), c(64, 47, 3);
  const std::vector<std::string> sizes = {"64x48", "32x32"};
  expect_error(Errc::SizeMismatch, sizes, [&] { compare_images(a, b); });
  expect_error(Errc::SizeMismatch, sizes, [&] { rmse(a, b); });
  expect_error(Errc::SizeMismatch, sizes, [&] { relmse(a, b); });
  expect_error(Errc::SizeMismatch, sizes, [&] { psnr(a, b); });
  expect_error(Errc::SizeMismatch, sizes, [&] { ssim(a, b); });
  expect_error(Errc::SizeMismatch, sizes, [&] { temporal_error(a, b); });
  expect_error(Errc::SizeMismatch, {"64x48", "64x47"}, [&] { compare_images(a, c); });
}

TEST(MetricsTest, FewerThanThreeChannelsOrEmptyIsInvalid) {
  const Image rgb(8, 8, 3), ya(8, 8, 2), empty;
  expect_error(Errc::InvalidArgument, {"channel"}, [&] { compare_images(rgb, ya); });
  expect_error(Errc::InvalidArgument, {"channel"}, [&] { ssim(ya, rgb); });
  expect_error(Errc::InvalidArgument, {"channel"}, [&] { temporal_error(ya, ya); });
  expect_error(Errc::InvalidArgument, {}, [&] { rmse(empty, empty); });
}

}  // namespace
}  // namespace mcr
