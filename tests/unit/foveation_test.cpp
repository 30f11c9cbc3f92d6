// Foveation (Immonen 2017, fig. 5.1): the parameter table helper, the blend
// between the inner and outer sets, and its effect on the three filters.
#include "kernels/foveation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "util/error.h"

namespace mcr {
namespace {

using testutil::Params;
using testutil::with;

ParamTable demo_table() {
  return with_foveation({ParamSpec::Float("sigma", 1.5, 0.0, 10.0, "blur"), ParamSpec::Int("radius", 2, 0, 9, "r"),
                         ParamSpec::Float("tau", 0.25, 0.0, 1.0, "t")},
                        {"sigma", "tau"});
}

const ParamSpec* find(const ParamTable& t, const std::string& name) {
  for (const ParamSpec& s : t)
    if (s.name == name) return &s;
  return nullptr;
}

TEST(FoveationTest, TableGetsOuterTwinsAndTheFiveParameters) {
  const ParamTable t = demo_table();
  std::vector<std::string> names;
  for (const ParamSpec& s : t) names.push_back(s.name);
  const std::vector<std::string> want = {"sigma", "sigma_outer", "radius", "tau", "tau_outer", "foveated",
                                         "gaze_x", "gaze_y", "inner_radius", "outer_radius"};
  EXPECT_EQ(names, want);
  const ParamSpec* twin = find(t, "sigma_outer");
  ASSERT_NE(twin, nullptr);
  EXPECT_EQ(twin->type, ParamType::Float);
  EXPECT_EQ(twin->min, 0.0);
  EXPECT_EQ(twin->max, 10.0);
  EXPECT_EQ(std::get<double>(twin->default_value), 1.5);
  EXPECT_EQ(std::get<bool>(find(t, "foveated")->default_value), false);
  EXPECT_THROW(with_foveation({ParamSpec::Int("radius", 2, 0, 9, "r")}, {"radius"}), Error);  // Float only
  EXPECT_THROW(with_foveation({}, {"nope"}), Error);
}

struct DemoParams {
  ParamTable table = demo_table();
  ParamSet params{"demo", &table};
};

TEST(FoveationTest, BlendIsZeroInsideOneOutsideLinearBetween) {
  DemoParams s;
  s.params.set("foveated", true);
  s.params.set("gaze_x", 0.25);
  s.params.set("gaze_y", 0.5);
  s.params.set("inner_radius", 0.1);
  s.params.set("outer_radius", 0.3);
  const int w = 300, h = 400;  // diagonal 500
  const Foveation fov(s.params, w, h);
  const double gx = 75, gy = 200;  // gaze in pixels; radii 50 and 150
  EXPECT_EQ(fov.blend(gx, gy), 0.0f);
  EXPECT_EQ(fov.blend(gx + 50, gy), 0.0f);  // on the inner circle: still inner
  EXPECT_EQ(fov.blend(gx, gy - 49.9), 0.0f);
  EXPECT_NEAR(fov.blend(gx + 100, gy), 0.5f, 1e-6);  // midway
  EXPECT_NEAR(fov.blend(gx + 60, gy + 80), 0.5f, 1e-6);  // distance 100 in another direction
  EXPECT_NEAR(fov.blend(gx + 75, gy), 0.25f, 1e-6);
  EXPECT_EQ(fov.blend(gx + 150, gy), 1.0f);
  EXPECT_EQ(fov.blend(gx, gy + 199), 1.0f);
  EXPECT_EQ(fov.blend_at(299, 399), 1.0f);
  // Parameters: inner at the gaze, outer beyond, linear between.
  s.params.set("sigma", 1.0);
  s.params.set("sigma_outer", 5.0);
  EXPECT_EQ(fov.value("sigma", fov.blend(gx, gy)), 1.0);
  EXPECT_EQ(fov.value("sigma", fov.blend(gx, gy + 180)), 5.0);
  EXPECT_NEAR(fov.value("sigma", fov.blend(gx + 100, gy)), 3.0, 1e-6);
  EXPECT_NEAR(fov.value("tau", fov.blend(gx + 100, gy)), 0.25, 1e-12);  // equal sets: constant
  EXPECT_TRUE(fov.varies("sigma"));
  EXPECT_FALSE(fov.varies("tau"));
  // The plane over a box holds the same values.
  const Roi box{70, 190, 80, 200};
  const std::vector<float> t = fov.blend_plane(box);
  for (int y = box.y0; y < box.y1; ++y)
    for (int x = box.x0; x < box.x1; ++x) EXPECT_EQ(t[std::size_t(y - box.y0) * 10 + (x - box.x0)], fov.blend_at(x, y));
}

TEST(FoveationTest, OffMeansInnerSetEverywhere) {
  DemoParams s;
  s.params.set("sigma_outer", 7.0);
  const Foveation fov(s.params, 100, 100);
  EXPECT_FALSE(fov.enabled());
  EXPECT_EQ(fov.blend(0, 0), 0.0f);
  EXPECT_EQ(fov.value("sigma", fov.blend(0, 0)), 1.5);
  EXPECT_FALSE(fov.varies("sigma"));
}

TEST(FoveationTest, EqualRadiiStep) {
  DemoParams s;
  s.params.set("foveated", true);
  s.params.set("inner_radius", 0.2);
  s.params.set("outer_radius", 0.2);
  const Foveation fov(s.params, 30, 40);  // gaze (15, 20), radius 10
  EXPECT_EQ(fov.blend(15 + 9.99, 20), 0.0f);
  EXPECT_EQ(fov.blend(15 + 10, 20), 0.0f);
  EXPECT_EQ(fov.blend(15 + 10.01, 20), 1.0f);
}

TEST(FoveationTest, OuterRadiusBelowInnerIsRejected) {
  DemoParams s;
  s.params.set("inner_radius", 0.4);
  s.params.set("outer_radius", 0.1);
  EXPECT_NO_THROW(check_foveation_params(s.params, "demo"));  // not foveated: ignored
  s.params.set("foveated", true);
  try {
    check_foveation_params(s.params, "demo");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::ParameterOutOfRange);
    EXPECT_NE(std::string(e.what()).find("outer_radius"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("demo"), std::string::npos);
  }
}

// ---------------------------------------------------------------------------
// The filters.

// Colour, normal, position and albedo (no depth), random.
Frame test_frame(int w, int h, unsigned seed) {
  using testutil::add_pass;
  using testutil::random_image;
  Frame f = testutil::colour_frame(random_image(w, h, 3, seed));
  f.path = "fovea.exr";
  add_pass(f, Role::Normal, random_image(w, h, 3, seed + 1, -1.0f, 1.0f));
  add_pass(f, Role::Position, random_image(w, h, 3, seed + 2, 0.0f, 3.0f));
  add_pass(f, Role::Albedo, random_image(w, h, 3, seed + 3, 0.1f, 1.0f));
  return f;
}

Image run(const std::string& filter, const Frame& frame, const Params& params, int nthreads = 0) {
  auto f = make_filter(filter);
  testutil::without_step_back(*f);  // the filters' own reach is what is compared
  for (const auto& [k, v] : params) f->set(k, v);
  f->commit();
  ExecOptions eo;
  eo.nthreads = nthreads;
  return f->execute(frame, eo);
}

// Inner set, outer set and the parameters they differ in, per filter.
// Colour sigmas in radiance units (colour_weight=absolute; the defaults are noise-relative).
struct Case {
  std::string filter;
  Params inner, outer;  // plain (non-foveated) parameter sets
  int reach;            // how far a pixel's result looks (all passes)
};

std::vector<Case> cases() {
  return {
      {"gaussian", {{"sigma", 0.4}}, {{"sigma", 1.3}}, 4},
      {"bilateral",
       {{"colour_weight", std::string("absolute")}, {"spatial_sigma", 0.7}, {"colour_sigma", 0.2}, {"normal_sigma", 0.3}, {"position_sigma", 1.0},
        {"albedo_sigma", 0.3}},
       {{"colour_weight", std::string("absolute")}, {"spatial_sigma", 1.6}, {"colour_sigma", 1.5}, {"normal_sigma", 2.0}, {"position_sigma", 5.0},
        {"albedo_sigma", 2.0}},
       5},
      {"atrous",
       {{"colour_weight", std::string("absolute")}, {"kernel_size", std::int64_t(3)}, {"iterations", std::int64_t(2)},
        {"colour_sigma", 0.1},
        {"normal_sigma", 0.3}, {"position_sigma", 0.2}, {"albedo_sigma", 0.2}},
       {{"colour_weight", std::string("absolute")}, {"kernel_size", std::int64_t(3)}, {"iterations", std::int64_t(2)},
        {"colour_sigma", 3.0},
        {"normal_sigma", 3.0}, {"position_sigma", 5.0}, {"albedo_sigma", 2.0}},
       3},
  };
}

// The foveated set: inner values as given, each differing one as "<name>_outer".
Params foveated(const Case& c) {
  Params p = c.inner;
  for (const auto& [k, v] : c.outer)
    if (c.inner.at(k) != v) p[k + "_outer"] = v;
  p["foveated"] = true;
  p["gaze_x"] = 0.5;
  p["gaze_y"] = 0.5;
  p["inner_radius"] = 0.25;
  p["outer_radius"] = 0.3;
  return p;
}

TEST(FoveationTest, FiltersUseTheInnerSetAtTheGazeAndTheOuterSetBeyond) {
  const int w = 64, h = 64;  // diagonal 90.5: inner radius 22.6 px, outer 27.2 px around (32, 32)
  const Frame frame = test_frame(w, h, 1);
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.filter);
    const Image fov = run(c.filter, frame, foveated(c));
    const Image in = run(c.filter, frame, c.inner);
    const Image out = run(c.filter, frame, c.outer);
    int inner_checked = 0, outer_checked = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double d = std::hypot(x + 0.5 - 32, y + 0.5 - 32);
        // Every pixel the result looks at must lie on the same side (multi-pass atrous).
        const bool all_inner = d + c.reach * std::sqrt(2.0) < 22.6;
        const bool all_outer = d - c.reach * std::sqrt(2.0) > 27.2;
        for (int ch = 0; ch < 3; ++ch) {
          if (all_inner) ASSERT_NEAR(fov.at(x, y, ch), in.at(x, y, ch), 2e-6) << x << "," << y;
          if (all_outer) ASSERT_NEAR(fov.at(x, y, ch), out.at(x, y, ch), 2e-6) << x << "," << y;
        }
        inner_checked += all_inner;
        outer_checked += all_outer;
      }
    EXPECT_GT(inner_checked, 500);
    EXPECT_GT(outer_checked, 500);
    // And in between it is neither.
    EXPECT_NE(fov.at(32 + 24, 32, 0), in.at(32 + 24, 32, 0));
    EXPECT_NE(fov.at(32 + 24, 32, 0), out.at(32 + 24, 32, 0));
  }
}

TEST(FoveationTest, FiltersWithEqualSetsEqualTheNonFoveatedOnes) {
  const Frame frame = test_frame(53, 37, 2);
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.filter);
    const Image plain = run(c.filter, frame, c.outer);
    Params eq = c.outer;
    for (const auto& [k, v] : c.outer)
      if (k.find("sigma") != std::string::npos) eq[k + "_outer"] = v;
    eq["foveated"] = true;
    eq["inner_radius"] = 0.05;
    eq["outer_radius"] = 0.2;
    EXPECT_EQ(run(c.filter, frame, eq).storage(), plain.storage());
  }
}

// Midway between the radii a single-pass filter uses the average parameters:
// checked on the bilateral, whose result at a pixel depends on its own sigmas only.
TEST(FoveationTest, MidwayIsTheLinearInterpolation) {
  const int w = 80, h = 60;  // diagonal 100: radii 10 and 30 around the centre of pixel (40, 30)
  const Frame frame = test_frame(w, h, 3);
  const Params fov = {{"foveated", true},           {"gaze_x", 40.5 / 80},       {"gaze_y", 30.5 / 60},
                      {"inner_radius", 0.1},        {"outer_radius", 0.3},       {"spatial_sigma", 0.5},
                      {"spatial_sigma_outer", 2.5}, {"colour_sigma", 0.2},       {"colour_sigma_outer", 1.0},
                      {"normal_sigma", 0.3},        {"normal_sigma_outer", 0.9}, {"radius", std::int64_t(8)},
                      {"colour_weight", std::string("absolute")}, {"albedo_sigma", 0.1}};
  const Params mid = {{"spatial_sigma", 1.5}, {"colour_sigma", 0.6}, {"normal_sigma", 0.6}, {"radius", std::int64_t(8)},
                      {"colour_weight", std::string("absolute")}, {"albedo_sigma", 0.1}};
  const Image a = run("bilateral", frame, fov), b = run("bilateral", frame, mid);
  // Pixels at distance 20 (t = 0.5) in four directions.
  for (auto [x, y] : {std::pair{60, 30}, std::pair{20, 30}, std::pair{40, 10}, std::pair{52, 46}})
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(a.at(x, y, ch), b.at(x, y, ch), 1e-5) << x << "," << y;
  EXPECT_NE(a.at(45, 30, 0), b.at(45, 30, 0));  // t = 0 there
}

}  // namespace
}  // namespace mcr
