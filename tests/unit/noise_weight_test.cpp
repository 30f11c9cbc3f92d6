// Noise-relative colour weight (filters/noise_weight.h): the variance estimate against
// closed forms, and the filters' colour_weight=noise against invariances it must have.
#include "kernels/noise_relative_colour.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "feature_filter_testutil.h"
#include "filters/image/atrous.h"
#include "filters/image/bilateral.h"

namespace mcr {
namespace {

using namespace testutil;

TEST(NoiseWeight, ConstantImageHasOnlyTheFloor) {
  const Image im(12, 10, 3, 0.25f);  // Y = 0.25
  const Roi box = Roi::all(12, 10);
  const std::vector<double> s2 = noise_variance(im, nullptr, box, 0);
  ASSERT_EQ(s2.size(), 120u);
  for (double v : s2) EXPECT_NEAR(v, 1e-6 * 0.25 * 0.25 + 1e-30, 1e-15);
}

TEST(NoiseWeight, LinearSignalIsNotNoise) {
  // A plane's 8-neighbour mean is the centre: residual 0 wherever the whole 3x3 window of
  // every residual the smoothing reads is inside the image (3 px from the border).
  Image im(20, 16, 3);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 20; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 0.25f + 0.015625f * x + 0.03125f * y;  // exact in float
  const std::vector<double> s2 = noise_variance(im, nullptr, Roi::all(20, 16), 0);
  for (int y = 3; y < 13; ++y)
    for (int x = 3; x < 17; ++x) {
      const double yl = 0.25 + 0.015625 * x + 0.03125 * y;
      EXPECT_NEAR(s2[std::size_t(y) * 20 + x], 1e-6 * yl * yl + 1e-30, 1e-12) << x << "," << y;
    }
}

TEST(NoiseWeight, WhiteNoiseVarianceIsRecovered) {
  // i.i.d. noise of standard deviation sd per channel: s^2 -> 3 sd^2 (+ the 1e-6 Y^2 floor).
  const int w = 256, h = 256;
  const double sd = 0.1, mean = 1.0;
  Image im(w, h, 3);
  std::mt19937 rng(3);
  std::normal_distribution<float> dist{float(mean), float(sd)};
  for (float& v : im.storage()) v = dist(rng);
  const std::vector<double> s2 = noise_variance(im, nullptr, Roi::all(w, h), 0);
  double acc = 0;
  for (double v : s2) acc += v;
  EXPECT_NEAR(acc / double(s2.size()), 3 * sd * sd + 1e-6 * mean * mean, 0.03 * 3 * sd * sd);
}

TEST(NoiseWeight, SampleCountDividesTheVariance) {
  // Per-sample variance with n samples per pixel: v = s^2 / n. Same noise image, n = 4 everywhere
  // read as 4 samples per pixel: the per-sample estimate is 4x the pixel one, divided by 4.
  const int w = 64, h = 64;
  Image im(w, h, 3);
  std::mt19937 rng(5);
  std::normal_distribution<float> dist(1.0f, 0.1f);
  for (float& v : im.storage()) v = dist(rng);
  const Image spp(w, h, 1, 4.0f);
  const std::vector<double> a = noise_variance(im, nullptr, Roi::all(w, h), 0);
  const std::vector<double> b = noise_variance(im, &spp, Roi::all(w, h), 0);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-9 * a[i]);
}

template <class F>
void scale_invariance() {
  // colour_weight=noise measures colour differences in noise units, so scaling the colour by
  // lambda scales the output by lambda (up to the 1e-30 floor); absolute units do not.
  Frame f = full_frame(40, 32, 11);
  Frame g = f;
  const float lambda = 1024.0f;  // a power of two: the scaled input is exact
  for (float& v : pass_image(g, Role::Colour).storage()) v *= lambda;
  const Params p = {{"colour_weight", std::string("noise")}, {"colour_sigma", 1.0}, {"normal_sigma", 1.0},
                    {"position_sigma", 1.5}, {"albedo_sigma", 0.8}};
  const Image a = run_filter<F>(f, p).out, b = run_filter<F>(g, p).out;
  double worst = 0;
  for (std::size_t i = 0; i < a.storage().size(); ++i)
    worst = std::max(worst, std::fabs(double(b.storage()[i]) / lambda - a.storage()[i]));
  EXPECT_LT(worst, 2e-5);
  const Params q = with(p, {{"colour_weight", std::string("absolute")}});
  const Image c = run_filter<F>(f, q).out, d = run_filter<F>(g, q).out;
  double diff = 0;
  for (std::size_t i = 0; i < c.storage().size(); ++i)
    diff = std::max(diff, std::fabs(double(d.storage()[i]) / lambda - c.storage()[i]));
  EXPECT_GT(diff, 1e-3);
}

TEST(NoiseWeight, AtrousIsScaleInvariant) { scale_invariance<AtrousFilter>(); }
TEST(NoiseWeight, BilateralIsScaleInvariant) { scale_invariance<BilateralFilter>(); }

TEST(NoiseWeight, NoiseFreeImageIsLeftAlone) {
  // A noise-free plane has s = 1e-3 Y wherever the estimate sees only the plane (3 px from
  // the border; there the clipped 8-neighbour mean is off-centre and reads as noise):
  // neighbours 1/64 apart are > 80 sigma away, weight 0, so those pixels keep their
  // value exactly in one pass (later passes compare with blurred border values, which may
  // come close). Absolute units blur the plane's border.
  Image im(24, 20, 3);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 24; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 0.25f + 0.015625f * x + 0.03125f * y;
  const Frame f = colour_frame(im);
  const Params p = with(all_off(), {{"use_colour", std::string("on")}, {"colour_weight", std::string("noise")},
                                    {"iterations", std::int64_t(1)}});
  const Image a = run_filter<AtrousFilter>(f, p).out;
  for (int y = 3; y < 17; ++y)
    for (int x = 3; x < 21; ++x)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(a.at(x, y, c), im.at(x, y, c)) << x << "," << y;
  const Image b = run_filter<AtrousFilter>(f, with(p, {{"colour_weight", std::string("absolute")}})).out;
  EXPECT_NE(b.at(0, 0, 0), im.at(0, 0, 0));
}

TEST(NoiseWeight, NonFiniteNeverLeaks) {
  Frame f = full_frame(30, 20, 4);
  Image& c = pass_image(f, Role::Colour);
  c.at(3, 3, 0) = kNaN;
  c.at(10, 7, 1) = kInf;
  c.at(20, 12, 2) = 1e30f;
  for (int iters : {1, 3}) {
    const Result r = run_filter<AtrousFilter>(
        f, {{"colour_weight", std::string("noise")}, {"iterations", std::int64_t(iters)}, {"firefly_k", 2.0}});
    EXPECT_EQ(r.repaired, 0u);
    for (float v : r.out.storage()) EXPECT_TRUE(std::isfinite(v));
  }
  const Result r = run_filter<BilateralFilter>(f, {{"colour_weight", std::string("noise")}});
  EXPECT_EQ(r.repaired, 0u);
}

}  // namespace
}  // namespace mcr
