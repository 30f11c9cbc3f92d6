// The outlier rule and its repairs (prepare/outliers.h) against hand-computed window statistics.
#include "prepare/outliers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "feature_filter_testutil.h"
#include "filters/registry.h"

namespace mcr {
namespace {

double lum(const float* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

// clamp_fireflies over the whole image, on a copy.
Image suppress_fireflies(const Image& in, int radius, double k, int nthreads, std::size_t* n = nullptr) {
  Image out = in;
  const std::size_t hits = clamp_fireflies(out, radius, k, Roi::all(in.width(), in.height()), nthreads);
  if (n) *n = hits;
  return out;
}

Image grey(int w, int h, float v) { return Image(w, h, 3, v); }

void set_rgb(Image& im, int x, int y, float r, float g, float b) {
  float* p = im.pixel(x, y);
  p[0] = r;
  p[1] = g;
  p[2] = b;
}

TEST(Fireflies, SpikeInFlatFieldIsClampedToOnePercentAboveTheMean) {
  // Neighbours all Y = 0.5: sd = 0, so lim = 0.5 + 0.01 * 0.5 = 0.505; the spike keeps its
  // colour ratios. Every other pixel is below its (spike-raised) mean: unchanged.
  Image in = grey(9, 9, 0.5f);
  set_rgb(in, 4, 4, 50.0f, 20.0f, 10.0f);
  std::size_t n = 0;
  const Image out = suppress_fireflies(in, 3, 2.0, 0, &n);
  EXPECT_EQ(n, 1u);
  const double s = 0.505 / (0.2126 * 50 + 0.7152 * 20 + 0.0722 * 10);
  EXPECT_NEAR(out.at(4, 4, 0), 50.0 * s, 1e-6);
  EXPECT_NEAR(out.at(4, 4, 1), 20.0 * s, 1e-6);
  EXPECT_NEAR(out.at(4, 4, 2), 10.0 * s, 1e-6);
  EXPECT_NEAR(lum(out.pixel(4, 4)), 0.505, 1e-6);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x)
      if (x != 4 || y != 4)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(out.at(x, y, c), 0.5f);
}

TEST(Fireflies, LimitIsMeanPlusKStandardDeviations) {
  // Centre of a 3x3 image, radius 1: neighbours grey 0,0,0,0,1,1,1,1 (grey: Y = value),
  // mu = 0.5, sd = 0.5, so with k = 2 the limit is 1.5.
  auto make = [](float centre) {
    Image im = grey(3, 3, 0.0f);
    for (auto [x, y] : {std::pair{2, 1}, std::pair{0, 2}, std::pair{1, 2}, std::pair{2, 2}}) set_rgb(im, x, y, 1, 1, 1);
    set_rgb(im, 1, 1, centre, centre, centre);
    return im;
  };
  const Image a = suppress_fireflies(make(3.0f), 1, 2.0, 0);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(a.at(1, 1, c), 1.5, 1e-6);
  const Image b = suppress_fireflies(make(1.4f), 1, 2.0, 0);  // below the limit
  for (int c = 0; c < 3; ++c) EXPECT_EQ(b.at(1, 1, c), 1.4f);
  const Image c3 = suppress_fireflies(make(3.0f), 1, 4.0, 0);  // limit 2.5
  EXPECT_NEAR(c3.at(1, 1, 1), 2.5, 1e-6);
}

TEST(Fireflies, OffDarkPixelsAndNonFinite) {
  Image in = grey(9, 9, 0.5f);
  set_rgb(in, 4, 4, 50.0f, 20.0f, 10.0f);
  // k = 0: a plain copy.
  const Image off = suppress_fireflies(in, 3, 0.0, 0);
  EXPECT_EQ(off.storage(), in.storage());
  // A dark dip is never raised.
  Image dip = grey(9, 9, 0.5f);
  set_rgb(dip, 4, 4, 0.0f, 0.0f, 0.0f);
  EXPECT_EQ(suppress_fireflies(dip, 3, 2.0, 0).storage(), dip.storage());
  // A non-finite neighbour takes no part in the statistics and stays as it is.
  Image nf = in;
  set_rgb(nf, 3, 4, std::numeric_limits<float>::quiet_NaN(), 1.0f, 1.0f);
  set_rgb(nf, 5, 4, std::numeric_limits<float>::infinity(), 1.0f, 1.0f);
  const Image out = suppress_fireflies(nf, 3, 2.0, 0);
  EXPECT_NEAR(lum(out.pixel(4, 4)), 0.505, 1e-6);
  EXPECT_TRUE(std::isnan(out.at(3, 4, 0)));
  EXPECT_TRUE(std::isinf(out.at(5, 4, 0)));
  // Thread count does not matter.
  Image rnd(40, 30, 3);
  unsigned s = 7;
  for (float& v : rnd.storage()) {
    s = s * 1664525u + 1013904223u;
    v = float(s >> 8) / float(1u << 24);
    if ((s & 63u) == 0) v *= 50.0f;
  }
  EXPECT_EQ(suppress_fireflies(rnd, 2, 2.0, 1).storage(), suppress_fireflies(rnd, 2, 2.0, 4).storage());
}

TEST(Fireflies, EveryFilterHasTheCommonParameters) {
  // On by default (k 8) in every image filter; off in bmfr, whose phase I sample limit
  // does that job (prepare/sample_limits.h).
  for (const std::string& name : image_filter_names()) {
    const auto f = make_filter(name);
    EXPECT_EQ(f->params().get_float("firefly_k"), name == "bmfr" ? 0.0 : 8.0) << name;
    EXPECT_EQ(f->params().get_int("firefly_radius"), 3) << name;
  }
}

TEST(Fireflies, AppliedBeforeTheFilter) {
  // box with firefly_k = box run on the suppressed image.
  Image in = grey(9, 9, 0.5f);
  set_rgb(in, 4, 4, 50.0f, 20.0f, 10.0f);
  const Frame f = testutil::colour_frame(in);
  auto a = make_filter("box");
  a->set("firefly_k", 2.0);
  a->commit();
  const Image out = a->execute(f);
  auto b = make_filter("box");  // box without the outlier step (on by default)
  b->set("firefly_k", 0.0);
  b->commit();
  const Image ref = b->execute(testutil::colour_frame(suppress_fireflies(in, 3, 2.0, 0)));
  for (std::size_t i = 0; i < out.storage().size(); ++i) EXPECT_FLOAT_EQ(out.storage()[i], ref.storage()[i]);
  EXPECT_NE(out.at(4, 4, 0), b->execute(f).at(4, 4, 0));
}

TEST(Fireflies, AfterDemodulationATextureEdgeIsNoOutlier) {
  // A bright texel (albedo 0.9 among 0.05) under constant light 0.8: its radiance stands
  // 18x above its window, but its illumination does not, so with demodulate=true nothing is
  // clamped and the box (of a constant illumination) gives back light x albedo everywhere.
  // A spike in the light itself (at 2,2) is still clamped.
  Image albedo = grey(9, 9, 0.05f);
  set_rgb(albedo, 4, 4, 0.9f, 0.9f, 0.9f);
  Image colour(9, 9, 3);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x)
      for (int c = 0; c < 3; ++c) colour.at(x, y, c) = 0.8f * albedo.at(x, y, c);
  colour.at(2, 2, 0) = colour.at(2, 2, 1) = colour.at(2, 2, 2) = 0.05f * 40.0f;
  Frame f = testutil::colour_frame(colour);
  testutil::add_pass(f, Role::Albedo, albedo);
  auto box = make_filter("box");
  box->set("radius", 0);  // identity: only suppression and (de)modulation act
  box->set("demodulate", true);
  box->set("firefly_k", 2.0);
  box->commit();
  const Image out = box->execute(f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(out.at(4, 4, c), 0.8f * 0.9f, 1e-6f);
    EXPECT_LT(out.at(2, 2, c), 0.05f * 2.0f);
  }
}

}  // namespace
}  // namespace mcr
