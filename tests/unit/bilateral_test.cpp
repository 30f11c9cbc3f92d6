// Cross-bilateral filter against a brute-force double-precision reference
// (bilateral_reference.h), plus closed forms and stress cases.
#include "filters/image/bilateral.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "kernels/cross_bilateral.h"
#include "kernels/foveation.h"
#include "bilateral_reference.h"
#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "util/error.h"
#include "util/isa.h"

namespace mcr {
namespace {

using namespace testutil;

Result run_on(const Frame& frame, const Params& params, int nthreads = 0, Roi roi = {}) {
  return run_filter<BilateralFilter>(frame, params, nthreads, roi);
}

Params mild() { return with(mild_features(), {{"spatial_sigma", 1.5}}); }

TEST(BilateralFilterTest, FastExpIsAccurate) {
  EXPECT_EQ(fast_exp_neg(0.0f), 1.0f);
  for (float e = 1e-6f; e < 86.0f; e *= 1.07f) {
    const double want = std::exp(-double(e));
    EXPECT_NEAR(fast_exp_neg(e), want, 3e-7 * want) << e;
  }
  EXPECT_EQ(fast_exp_neg(86.0f), 0.0f);
  EXPECT_EQ(fast_exp_neg(1e30f), 0.0f);
  EXPECT_EQ(fast_exp_neg(kInf), 0.0f);
  EXPECT_EQ(fast_exp_neg(kNaN), 0.0f);
}

// Every feature weight off: a plain Gaussian convolution, clipped and renormalised.
TEST(BilateralFilterTest, AllWeightsOffIsGaussianConvolution) {
  const Frame f = full_frame(27, 19, 1);
  for (double ss : {0.6, 1.5, 2.2}) {
    SCOPED_TRACE(ss);
    const Image got = run_on(f, with(all_off(), {{"spatial_sigma", ss}})).out;
    const Image& in = f.image(Role::Colour);
    const int r = int(std::ceil(3 * ss - 1e-6));
    for (int y = 0; y < f.height; ++y)
      for (int x = 0; x < f.width; ++x) {
        double s[3] = {0, 0, 0}, sw = 0;
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) {
            if (x + dx < 0 || y + dy < 0 || x + dx >= f.width || y + dy >= f.height) continue;
            const double wq = std::exp(-(dx * dx + dy * dy) / (2 * ss * ss));
            for (int c = 0; c < 3; ++c) s[c] += wq * in.at(x + dx, y + dy, c);
            sw += wq;
          }
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(got.at(x, y, c), s[c] / sw, 1e-5) << x << "," << y;
      }
  }
}

TEST(BilateralFilterTest, MatchesReferenceWithEveryFeature) {
  const Frame f = full_frame(33, 21, 2);
  const Params p = {{"spatial_sigma", 1.7}, {"colour_sigma", 0.4}, {"normal_sigma", 0.8}, {"position_sigma", 0.9},
                    {"albedo_sigma", 0.5}, {"use_depth", std::string("on")}, {"depth_sigma", 0.7}};
  expect_close(run_on(f, p).out, bilateral_reference(f, p), 1e-4);
  // One, two, three features, and a fixed radius larger than 3 sigma.
  expect_close(run_on(f, with(all_off(), {{"use_colour", std::string("on")}})).out,
               bilateral_reference(f, with(all_off(), {{"use_colour", std::string("on")}})), 1e-4, "colour");
  const Params two = with(all_off(), {{"use_colour", std::string("on")}, {"use_normal", std::string("on")}});
  expect_close(run_on(f, two).out, bilateral_reference(f, two), 1e-4, "two");
  const Params three = with(two, {{"use_position", std::string("on")}, {"radius", std::int64_t(7)}});
  expect_close(run_on(f, three).out, bilateral_reference(f, three), 1e-4, "three");
}

TEST(BilateralFilterTest, TinyFeatureSigmaIsIdentity) {
  Frame f = full_frame(20, 14, 3);  // random normals: every pair differs
  for (const char* n : {"normal", "position", "albedo", "colour"}) {
    SCOPED_TRACE(n);
    const Params p = with(all_off(), {{std::string("use_") + n, std::string("on")}, {std::string(n) + "_sigma", 1e-6}});
    const Image out = run_on(f, p).out;
    EXPECT_EQ(out.storage(), f.image(Role::Colour).storage());
  }
}

TEST(BilateralFilterTest, HugeFeatureSigmaIsGaussian) {
  const Frame f = full_frame(20, 14, 4);
  const Image gauss = run_on(f, with(all_off(), {{"spatial_sigma", 1.2}})).out;
  const Params p = {{"spatial_sigma", 1.2}, {"colour_sigma", 1e6}, {"normal_sigma", 1e6}, {"position_sigma", 1e6},
                    {"albedo_sigma", 1e6}, {"use_depth", std::string("on")}, {"depth_sigma", 1e6}};
  expect_close(run_on(f, p).out, gauss, 1e-5);
}

TEST(BilateralFilterTest, SpatialSigmaLimits) {
  const Frame f = full_frame(15, 10, 5);
  EXPECT_EQ(run_on(f, {{"spatial_sigma", 0.0}}).out.storage(), f.image(Role::Colour).storage());
  const Params big = {{"spatial_sigma", 21.0}};  // radius 63 over a 15x10 image
  expect_close(run_on(f, big).out, bilateral_reference(f, big), 1e-4);
  BilateralFilter b;
  EXPECT_THROW(b.set("spatial_sigma", 22.0), Error);
  EXPECT_THROW(b.set("normal_sigma", 0.0), Error);  // off is use_normal=off, never sigma 0
  EXPECT_THROW(b.set("radius", std::int64_t(65)), Error);
}

// Left half faces +z, right half +x; colours differ across the edge. With the
// normal weight only, pixels next to the edge average their own side only.
TEST(BilateralFilterTest, NormalAndPositionEdgesArePreserved) {
  const TwoSided s = two_sided(32, 24);
  for (Role guide : {Role::Normal, Role::Position}) {
    Frame f = colour_frame(s.colour);
    add_pass(f, guide, guide == Role::Normal ? s.normal : s.position);
    const Params p = with(all_off(), {{"spatial_sigma", 3.0},
                                      {guide == Role::Normal ? "use_normal" : "use_position", std::string("on")},
                                      {"normal_sigma", 0.1},
                                      {"position_sigma", 0.1}});
    expect_edge_kept_and_flat_smoothed(run_on(f, p).out, s.colour, 1, 10);
  }
}

TEST(BilateralFilterTest, ColourWeightStopsFireflies) {
  Image in(15, 15, 3, 0.5f);
  in.at(7, 7, 0) = 1e6f;
  Frame f = colour_frame(in);
  // firefly_k=0: the colour weight alone (then the clamp alone), not the common outlier step.
  const Params own = with(all_off(), {{"use_colour", std::string("on")}, {"spatial_sigma", 2.0}, {"firefly_k", 0.0}});
  const Image out = run_on(f, own).out;
  EXPECT_FLOAT_EQ(out.at(8, 7, 0), 0.5f);  // neighbours ignore it
  const Image clamped = run_on(f, with(own, {{"clamp", 1.0}})).out;
  EXPECT_LE(clamped.at(7, 7, 0), 1.0f);
}

TEST(BilateralFilterTest, AbsentFeaturesAreDroppedWithANoteOrRequired) {
  const Frame f = colour_frame(random_image(10, 8, 3, 7));
  Result r = run_on(f, {});
  EXPECT_TRUE(has_note(r, "normal weight dropped"));
  EXPECT_TRUE(has_note(r, "position weight dropped"));
  expect_close(r.out, bilateral_reference(f, {}), 1e-4);
  try {
    run_on(f, {{"use_normal", std::string("on")}});
    FAIL() << "use_normal=on without a normal pass must throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::MissingPass);
    EXPECT_NE(std::string(e.what()).find("normal"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("test.exr"), std::string::npos);
  }
  // No feature note with every feature off (firefly_k=0: no outlier step, whose count is a note).
  EXPECT_TRUE(run_on(f, with(all_off(), {{"firefly_k", 0.0}})).notes.empty());
}

TEST(BilateralFilterTest, ConstantImageAndEqualFeatures) {
  expect_constant_stays_constant(run_on, {{"spatial_sigma", 2.0}});
}

TEST(BilateralFilterTest, DegenerateShapes) {
  expect_degenerate_shapes_match(run_on, bilateral_reference, mild(), {17, 3});
}

TEST(BilateralFilterTest, TinyAndHugeValues) {
  expect_tiny_and_huge_values_handled(
      run_on, bilateral_reference,
      {with(mild(), {{"use_depth", std::string("off")}}), with(all_off(), {{"spatial_sigma", 1.5}})},
      with(all_off(), {{"spatial_sigma", 3.0}}));
}

// NaN and Inf in the colour and in each feature: finite output, nothing
// repaired by the safety net, and exactly the documented policy (the reference).
TEST(BilateralFilterTest, NonFiniteColourAndFeaturesFollowThePolicy) {
  const Params p = {{"spatial_sigma", 1.5}, {"colour_sigma", 0.6}, {"normal_sigma", 1.0}, {"position_sigma", 1.0},
                    {"albedo_sigma", 0.8}, {"use_depth", std::string("on")}, {"depth_sigma", 1.0}};
  for (Role role : kFeatureRoles) {
    SCOPED_TRACE(role_name(role));
    Frame f = full_frame(19, 15, 9);
    poison(pass_image(f, role), Roi{12, 0, 17, 3});  // a blob: centres inside have no usable neighbour
    Result r = run_on(f, p);
    ASSERT_NO_FATAL_FAILURE(expect_finite_unrepaired(r));
    expect_close(r.out, bilateral_reference(f, p), 1e-4);
    // A 3x3 window inside the blob has no usable sample: the pixel keeps its colour (if finite).
    const Params narrow = with(p, {{"spatial_sigma", 0.3}});
    const Result nr = run_on(f, narrow);
    expect_close(nr.out, bilateral_reference(f, narrow), 1e-4);
    if (role != Role::Colour)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(nr.out.at(14, 1, c), f.image(Role::Colour).at(14, 1, c));
    // With the feature off the non-finite values do not matter (colour aside).
    if (role != Role::Colour) {
      const Params off = with(p, {{std::string("use_") + role_name(role), std::string("off")}});
      expect_close(run_on(f, off).out, bilateral_reference(f, off), 1e-4);
    }
  }
}

TEST(BilateralFilterTest, ZeroAlbedoWithDemodulation) {
  Frame f = zero_albedo_frame();
  pass_image(f, Role::Albedo).at(3, 3, 0) = kNaN;
  expect_finite_unrepaired(run_on(f, {{"demodulate", true}}));
}

TEST(BilateralFilterTest, IdenticalForOneAndTwoThreads) {
  Frame f = full_frame(67, 41, 11);
  pass_image(f, Role::Normal).at(5, 5, 1) = kNaN;
  pass_image(f, Role::Colour).at(50, 20, 0) = kInf;
  expect_same_for_one_and_two_threads(
      run_on, f,
      {mild(), with(mild(), {{"foveated", true}, {"spatial_sigma", 0.5}, {"spatial_sigma_outer", 3.0},
                             {"colour_sigma_outer", 2.0}, {"inner_radius", 0.05}})});
}

TEST(BilateralFilterTest, RegionChangesOnlyPixelsInside) {
  expect_region_changes_only_inside(run_on, full_frame(30, 20, 12), Roi{7, 3, 19, 11}, mild());
}

// The kernel is built for several instruction sets; each must implement the same filter.
TEST(BilateralFilterTest, EveryInstructionSetMatchesTheReference) {
  Frame f = full_frame(37, 23, 21);
  pass_image(f, Role::Normal).at(3, 9, 2) = kNaN;
  pass_image(f, Role::Colour).at(30, 2, 1) = kInf;
  const Params p = {{"spatial_sigma", 1.4}, {"use_depth", std::string("on")}, {"normal_sigma", 0.9},
                    {"position_sigma", 1.2}, {"albedo_sigma", 0.6}};
  const Params fov = with(p, {{"foveated", true}, {"spatial_sigma", 0.6}, {"spatial_sigma_outer", 2.0},
                              {"colour_sigma_outer", 1.5}, {"inner_radius", 0.05}});
  const int ran = for_each_isa([&](Isa level) {
    EXPECT_EQ(isa(), level);
    expect_close(run_on(f, p).out, bilateral_reference(f, p), 1e-4);
    EXPECT_EQ(run_on(f, fov, 1).out.storage(), run_on(f, fov, 2).out.storage());
  });
  EXPECT_GE(ran, 1);
  EXPECT_THROW(parse_isa("neon512", "MCRECON_ISA"), Error);
}

TEST(BilateralFilterTest, TableAndPolicy) {
  const FilterInfo& info = filter_info("bilateral");
  for (const char* n : {"spatial_sigma", "spatial_sigma_outer", "radius", "use_colour", "colour_sigma",
                        "colour_sigma_outer", "use_normal", "normal_sigma_outer", "use_position", "position_sigma",
                        "use_albedo", "albedo_sigma", "use_depth", "depth_sigma_outer", "clamp", "foveated", "gaze_x",
                        "gaze_y", "inner_radius", "outer_radius", "demodulate"}) {
    bool found = false;
    for (const ParamSpec& s : info.params) found = found || s.name == n;
    EXPECT_TRUE(found) << n;
  }
  EXPECT_NE(info.nonfinite_policy.find("weight 0"), std::string::npos);
}

TEST(BilateralFilterTest, DefaultsFollowTheNoise) {
  BilateralFilter f;
  EXPECT_EQ(f.params().get_enum("colour_weight"), "noise");
  EXPECT_EQ(f.params().get_float("colour_sigma"), 4.0);
  EXPECT_EQ(f.params().get_float("albedo_sigma"), 0.05);
  expect_defaults_follow_the_noise<BilateralFilter>();
}

}  // namespace
}  // namespace mcr
