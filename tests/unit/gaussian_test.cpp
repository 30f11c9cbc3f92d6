// Gaussian (Simple Blur) against a brute-force 2D convolution, on both paths:
// separable (constant sigma) and per-pixel (foveated sigma).
#include "filters/image/gaussian.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "kernels/cross_bilateral.h"
#include "kernels/foveation.h"
#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "util/error.h"
#include "util/isa.h"

namespace mcr {
namespace {

using testutil::kInf;
using testutil::kNaN;
using testutil::Params;
using testutil::Result;

Frame frame_of(const Image& colour) { return testutil::colour_frame(colour); }

Image random_image(int w, int h, unsigned seed, float lo = 0.0f, float hi = 1.0f) {
  return testutil::random_image(w, h, 3, seed, lo, hi);
}

Result run_on(const Frame& frame, const Params& params, int nthreads = 0, Roi roi = {}) {
  return testutil::run_filter<GaussianFilter>(frame, params, nthreads, roi);
}

Image run_gauss(const Image& colour, double sigma, int nthreads = 0, Roi roi = {}) {
  return run_on(frame_of(colour), {{"sigma", sigma}}, nthreads, roi).out;
}

// The documented kernel: exp(-d^2/(2 sigma^2)) over |dx|,|dy| <= ceil(3 sigma),
// clipped at the borders and renormalised, non-finite pixels left out, 0 if none.
void brute(const Image& in, int x, int y, double sigma, double out[3]) {
  const int r = sigma > 0 ? int(std::ceil(3 * sigma - 1e-6)) : 0;
  double s[3] = {0, 0, 0}, sw = 0;
  for (int yy = y - r; yy <= y + r; ++yy)
    for (int xx = x - r; xx <= x + r; ++xx) {
      if (xx < 0 || yy < 0 || xx >= in.width() || yy >= in.height()) continue;
      const float* p = in.pixel(xx, yy);
      if (!testutil::finite_n(p, 3)) continue;
      const double d2 = double(xx - x) * (xx - x) + double(yy - y) * (yy - y);
      const double w = sigma > 0 ? std::exp(-d2 / (2 * sigma * sigma)) : 1.0;
      for (int c = 0; c < 3; ++c) s[c] += w * p[c];
      sw += w;
    }
  for (int c = 0; c < 3; ++c) out[c] = sw > 0 ? s[c] / sw : 0.0;
}

void expect_brute(const Image& in, const Image& out, const std::function<double(int, int)>& sigma_at,
                  double rel = 2e-5) {
  testutil::expect_each_pixel_near(
      in, out, [&](int x, int y, double want[3]) { brute(in, x, y, sigma_at(x, y), want); }, rel,
      [&](int x, int y) { return testing::Message() << " sigma " << sigma_at(x, y); });
}

auto constant_sigma(double s) {
  return [s](int, int) { return s; };
}

TEST(GaussianFilterTest, MatchesBruteForce2DConvolution) {
  for (double sigma : {0.4, 1.0, 1.7, 3.0}) {
    SCOPED_TRACE(sigma);
    const Image in = random_image(29, 21, unsigned(sigma * 10));
    expect_brute(in, run_gauss(in, sigma), constant_sigma(sigma));
  }
}

TEST(GaussianFilterTest, SigmaZeroIsIdentity) {
  const Image in = random_image(17, 11, 1);
  EXPECT_EQ(run_gauss(in, 0.0).storage(), in.storage());
}

TEST(GaussianFilterTest, RadiusIsCeilThreeSigma) {
  EXPECT_EQ(gaussian_radius(0.0), 0);
  EXPECT_EQ(gaussian_radius(0.1), 1);
  EXPECT_EQ(gaussian_radius(1.0), 3);
  EXPECT_EQ(gaussian_radius(8.0 / 3.0), 8);
  EXPECT_EQ(gaussian_radius(21.0), 63);
  // A single bright pixel spreads exactly ceil(3 sigma) pixels, no further.
  Image in(31, 1, 3, 0.0f);
  in.at(15, 0, 0) = 1.0f;
  const Image out = run_gauss(in, 1.5);  // r = 5
  EXPECT_GT(out.at(10, 0, 0), 0.0f);
  EXPECT_EQ(out.at(9, 0, 0), 0.0f);
  EXPECT_GT(out.at(20, 0, 0), 0.0f);
  EXPECT_EQ(out.at(21, 0, 0), 0.0f);
}

TEST(GaussianFilterTest, ConstantImageStaysConstant) {
  for (float v : {0.0f, 0.375f, -2.5f, 1e-30f, 1e30f, 3.3e38f, -3.3e38f, FLT_MAX}) {
    Image in(13, 9, 3, v);
    Result r = run_on(frame_of(in), {{"sigma", 2.0}});
    EXPECT_EQ(r.repaired, 0u);
    for (float o : r.out.storage()) ASSERT_NEAR(o, v, 1e-6 * std::fabs(v)) << "constant " << v;
  }
}

TEST(GaussianFilterTest, SigmaAtRangeLimits) {
  const Image in = random_image(12, 7, 3);
  expect_brute(in, run_gauss(in, 21.0), constant_sigma(21.0));  // window far larger than the image
  expect_brute(in, run_gauss(in, 1e-3), constant_sigma(1e-3));  // neighbours weigh exp(-5e5) = 0
  EXPECT_EQ(run_gauss(in, 1e-3).storage(), in.storage());
  GaussianFilter f;
  EXPECT_THROW(f.set("sigma", 21.5), Error);
  EXPECT_THROW(f.set("sigma", -0.1), Error);
}

TEST(GaussianFilterTest, DegenerateShapes) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{1, 9}, std::pair{9, 1}, std::pair{2, 1}, std::pair{1, 2}}) {
    const Image in = random_image(w, h, unsigned(w * 31 + h));
    for (double s : {0.0, 0.7, 2.0}) {
      SCOPED_TRACE(testing::Message() << w << "x" << h << " sigma=" << s);
      expect_brute(in, run_gauss(in, s), constant_sigma(s));
    }
  }
}

TEST(GaussianFilterTest, NonFinitePixelsGetWeightZero) {
  Image in = random_image(15, 12, 3);
  in.at(4, 4, 0) = kNaN;
  in.at(1, 1, 1) = kInf;
  in.at(1, 1, 0) = 1000.0f;  // R finite, the pixel is still left out
  in.at(7, 2, 2) = -kInf;
  for (double s : {0.8, 2.0}) {
    Result r = run_on(frame_of(in), {{"sigma", s}});
    ASSERT_NO_FATAL_FAILURE(testutil::expect_finite_unrepaired(r));
    expect_brute(in, r.out, constant_sigma(s));
    EXPECT_LT(r.out.at(1, 0, 0), 1.5f);  // the 1000 never leaks
  }
}

TEST(GaussianFilterTest, WindowWithoutFinitePixelGivesZero) {
  Image in(9, 9, 3, kNaN);
  in.at(8, 8, 0) = 2.0f;
  in.at(8, 8, 1) = 4.0f;
  in.at(8, 8, 2) = 6.0f;
  Result r = run_on(frame_of(in), {{"sigma", 0.5}});  // r = 2
  EXPECT_EQ(r.repaired, 0u);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(r.out.at(0, 0, c), 0.0f);
  EXPECT_FLOAT_EQ(r.out.at(6, 6, 0), 2.0f);
  EXPECT_FLOAT_EQ(r.out.at(7, 8, 2), 6.0f);
  Image all(5, 4, 3, kInf);
  Result z = run_on(frame_of(all), {{"sigma", 1.0}});
  EXPECT_EQ(z.repaired, 0u);
  for (float v : z.out.storage()) EXPECT_EQ(v, 0.0f);
}

TEST(GaussianFilterTest, TinyAndHugeValuesNeitherUnderflowNorOverflow) {
  Image in(40, 30, 3, 1e-30f);
  in.at(5, 5, 0) = 1e30f;
  in.at(5, 5, 1) = -1e30f;
  Result r = run_on(frame_of(in), {{"sigma", 1.0}});
  EXPECT_EQ(r.repaired, 0u);
  expect_brute(in, r.out, constant_sigma(1.0), 1e-5);
  EXPECT_NEAR(r.out.at(30, 20, 0), 1e-30f, 1e-36f);
  // Sums of many values near FLT_MAX must not overflow.
  Image big(20, 20, 3, FLT_MAX);
  big.at(3, 3, 1) = -FLT_MAX;
  Result b = run_on(frame_of(big), {{"sigma", 3.0}});
  ASSERT_NO_FATAL_FAILURE(testutil::expect_finite_unrepaired(b));
  EXPECT_NEAR(b.out.at(15, 15, 0), FLT_MAX, 1e-6 * FLT_MAX);
}

TEST(GaussianFilterTest, ZeroAlbedoWithDemodulation) {
  Frame f = frame_of(random_image(16, 16, 4));
  Pass a;
  a.role = Role::Albedo;
  a.name = "Denoising Albedo";
  a.image = Image(16, 16, 3, 0.0f);
  f.passes.push_back(a);
  testutil::expect_finite_unrepaired(run_on(f, {{"sigma", 1.5}, {"demodulate", true}}));
}

TEST(GaussianFilterTest, FireflyClamp) {
  Image in(11, 11, 3, 0.5f);
  in.at(5, 5, 0) = 1e6f;
  // firefly_k=0: the clamp alone, without the common outlier step (on by default).
  const Image loose = run_on(frame_of(in), {{"sigma", 1.0}, {"firefly_k", 0.0}}).out;
  const Image clamped = run_on(frame_of(in), {{"sigma", 1.0}, {"clamp", 1.0}, {"firefly_k", 0.0}}).out;
  EXPECT_GT(loose.at(5, 5, 0), 1e4f);
  EXPECT_LE(clamped.at(5, 5, 0), 1.0f);
  EXPECT_GE(clamped.at(5, 5, 0), 0.5f);
}

TEST(GaussianFilterTest, IdenticalForOneAndTwoThreads) {
  Image in = random_image(70, 37, 5);
  in.at(10, 10, 1) = kNaN;
  for (const Params& p : {Params{{"sigma", 2.0}},
                          Params{{"sigma", 0.5}, {"sigma_outer", 3.0}, {"foveated", true}, {"inner_radius", 0.05}}}) {
    const Image one = run_on(frame_of(in), p, 1).out;
    const Image two = run_on(frame_of(in), p, 2).out;
    EXPECT_EQ(one.storage(), two.storage());
  }
}

TEST(GaussianFilterTest, RegionChangesOnlyPixelsInside) {
  const Image in = random_image(30, 20, 8);
  const Roi roi{7, 3, 19, 11};
  for (const Params& p : {Params{{"sigma", 1.5}},
                          Params{{"sigma", 0.5}, {"sigma_outer", 2.0}, {"foveated", true}, {"inner_radius", 0.05}}}) {
    ASSERT_NO_FATAL_FAILURE(
        testutil::expect_only_region_changed(run_on(frame_of(in), p, 0, roi).out, run_on(frame_of(in), p).out, in, roi));
  }
}

// Per-pixel sigma: the foveated path against the brute force with each pixel's
// own sigma = inner + t (outer - inner).
TEST(GaussianFilterTest, FoveatedMatchesPerPixelBruteForce) {
  const Image in = random_image(48, 40, 9);
  const Params p{{"sigma", 0.3}, {"sigma_outer", 2.5}, {"foveated", true}, {"gaze_x", 0.3}, {"gaze_y", 0.6},
                 {"inner_radius", 0.1}, {"outer_radius", 0.4}};
  GaussianFilter f;
  for (const auto& [k, v] : p) f.set(k, v);
  const Foveation fov(f.params(), 48, 40);
  const Image out = run_on(frame_of(in), p).out;
  expect_brute(in, out, [&](int x, int y) { return fov.value("sigma", fov.blend_at(x, y)); }, 1e-4);
}

TEST(GaussianFilterTest, FoveatedPathOnEveryInstructionSet) {
  Image in = random_image(37, 29, 19);
  in.at(3, 3, 0) = kNaN;
  const Params p{{"sigma", 0.3}, {"sigma_outer", 1.8}, {"foveated", true}, {"inner_radius", 0.05}};
  GaussianFilter f;
  for (const auto& [k, v] : p) f.set(k, v);
  const Foveation fov(f.params(), 37, 29);
  const int ran = testutil::for_each_isa([&](Isa) {
    expect_brute(in, run_on(frame_of(in), p).out, [&](int x, int y) { return fov.value("sigma", fov.blend_at(x, y)); },
                 1e-4);
  });
  EXPECT_GE(ran, 1);
}

TEST(GaussianFilterTest, FoveatedInnerAtGazeOuterBeyond) {
  const Image in = random_image(64, 64, 10);
  const Params p{{"sigma", 0.0}, {"sigma_outer", 2.0}, {"foveated", true}, {"inner_radius", 0.1},
                 {"outer_radius", 0.3}};
  const Image fov = run_on(frame_of(in), p).out;
  const Image outer = run_gauss(in, 2.0);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(fov.at(32, 32, c), in.at(32, 32, c));  // sigma 0 at the gaze: untouched
    EXPECT_EQ(fov.at(30, 33, c), in.at(30, 33, c));
    EXPECT_NEAR(fov.at(0, 0, c), outer.at(0, 0, c), 1e-5);  // corner: outer sigma
    EXPECT_NEAR(fov.at(63, 2, c), outer.at(63, 2, c), 1e-5);
  }
}

TEST(GaussianFilterTest, FoveatedWithEqualSetsEqualsPlain) {
  const Image in = random_image(40, 30, 11);
  const Image plain = run_gauss(in, 1.3);
  const Image fov = run_on(frame_of(in), {{"sigma", 1.3}, {"sigma_outer", 1.3}, {"foveated", true}}).out;
  EXPECT_EQ(plain.storage(), fov.storage());
}

TEST(GaussianFilterTest, ParameterChecks) {
  auto f = make_filter("gaussian");
  EXPECT_EQ(f->params().get_float("sigma"), 1.0);
  EXPECT_EQ(f->params().get_float("sigma_outer"), 1.0);
  f->set("foveated", true);
  f->set("inner_radius", 0.5);
  f->set("outer_radius", 0.2);
  try {
    f->commit();
    FAIL() << "outer_radius < inner_radius must be rejected";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::ParameterOutOfRange);
    EXPECT_NE(std::string(e.what()).find("outer_radius"), std::string::npos);
  }
  f->set("foveated", false);
  EXPECT_NO_THROW(f->commit());
  EXPECT_FALSE(f->info().nonfinite_policy.empty());
}

}  // namespace
}  // namespace mcr
