// Constant or absent feature passes (kernels/feature_activity.h) are dropped by every
// feature-aware filter, with a note, and the output is that of the filter with the
// feature switched off (bilateral, atrous: use_<f>=off; guided: the guide without the
// pass; pwaf: the frame without the pass; bmfr: the fit of a frame whose feature varies
// in one block only, whose other blocks then drop the column in the QR).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "feature_filter_testutil.h"
#include "filters/image/atrous.h"
#include "filters/image/bilateral.h"
#include "filters/image/guided.h"
#include "filters/image/pwaf.h"
#include "filters/registry.h"
#include "util/error.h"

namespace mcr {
namespace {

using namespace testutil;

// A textured flat wall facing the camera: one normal, one depth everywhere, positions
// spread across it, albedo texture, noisy colour.
Frame wall_frame(int w, int h, unsigned seed) {
  Frame f = colour_frame(random_image(w, h, 3, seed, 0.0f, 1.0f));
  add_pass(f, Role::Normal, Image(w, h, 3, 0.0f));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) pass_image(f, Role::Normal).pixel(x, y)[2] = 1.0f;
  Image pos(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = pos.pixel(x, y);
      p[0] = 0.02f * float(x);
      p[1] = 0.02f * float(y);
      p[2] = 5.0f;
    }
  add_pass(f, Role::Position, pos);
  add_pass(f, Role::Albedo, random_image(w, h, 3, seed + 1, 0.2f, 0.9f));
  add_pass(f, Role::Depth, Image(w, h, 1, 5.0f));
  return f;
}

Frame without(Frame f, Role r) {
  for (std::size_t i = 0; i < f.passes.size(); ++i)
    if (f.passes[i].role == r) {
      f.passes.erase(f.passes.begin() + std::ptrdiff_t(i));
      break;
    }
  return f;
}

template <class F>
void expect_constant_normal_and_depth_skipped(const Params& base) {
  const Frame f = wall_frame(48, 40, 7);
  const Params on = with(base, {{"use_depth", std::string("on")}});
  const Result skip = run_filter<F>(f, on);
  const Result off =
      run_filter<F>(f, with(base, {{"use_normal", std::string("off")}, {"use_depth", std::string("off")}}));
  EXPECT_TRUE(has_note(skip, "normal pass is constant over the frame (0.000, 0.000, 1.000): normal weight not used"));
  EXPECT_TRUE(has_note(skip, "depth pass is constant over the frame (5.000): depth weight not used"));
  EXPECT_FALSE(has_note(skip, "position pass is constant"));
  EXPECT_FALSE(has_note(off, "pass is constant"));
  expect_close(skip.out, off.out, 1e-5, "constant normal and depth");
  EXPECT_GT(changed(skip.out, f.image(Role::Colour)), 0.5);  // it filtered
}

TEST(ConstantFeatureSkip, BilateralDropsConstantNormalAndDepth) {
  expect_constant_normal_and_depth_skipped<BilateralFilter>({{"colour_sigma", 0.5}});
}

TEST(ConstantFeatureSkip, BilateralFirstOrderDropsConstantNormalAndDepth) {
  expect_constant_normal_and_depth_skipped<BilateralFilter>(
      {{"colour_sigma", 0.5}, {"order", std::int64_t(1)}, {"spatial_sigma", 1.5}});
}

TEST(ConstantFeatureSkip, AtrousDropsConstantNormalAndDepth) {
  expect_constant_normal_and_depth_skipped<AtrousFilter>({{"colour_sigma", 0.5}});
}

// normal_sigma 0.2: the tolerance is 0.004 x 0.2 = 0.0008 per channel.
TEST(ConstantFeatureSkip, NormalVaryingJustOverTheToleranceIsUsed) {
  for (const auto& [dz, skipped] : {std::pair{0.0009f, false}, std::pair{0.0007f, true}}) {
    Frame f = wall_frame(32, 24, 3);
    pass_image(f, Role::Normal).pixel(31, 23)[2] = 1.0f - dz;
    for (bool atrous : {false, true}) {
      const Params p = {{"colour_sigma", 0.5}, {"normal_sigma", 0.2}};
      const Result r = atrous ? run_filter<AtrousFilter>(f, p) : run_filter<BilateralFilter>(f, p);
      EXPECT_EQ(has_note(r, "normal pass is constant"), skipped) << "dz " << dz << (atrous ? " atrous" : " bilateral");
    }
  }
}

TEST(ConstantFeatureSkip, AllNonFiniteNormalIsAbsent) {
  Frame f = wall_frame(32, 24, 5);
  for (float& v : pass_image(f, Role::Normal).storage()) v = kNaN;
  for (bool atrous : {false, true}) {
    const Params p = {{"colour_sigma", 0.5}};
    const Params off = with(p, {{"use_normal", std::string("off")}});
    const Result r = atrous ? run_filter<AtrousFilter>(f, p) : run_filter<BilateralFilter>(f, p);
    const Result o = atrous ? run_filter<AtrousFilter>(f, off) : run_filter<BilateralFilter>(f, off);
    EXPECT_TRUE(has_note(r, "normal pass has no finite value over the frame: normal weight not used"));
    expect_close(r.out, o.out, 1e-5, atrous ? "atrous" : "bilateral");
  }
}

// A constant normal with a few NaN pixels: dropped, but those pixels stay unusable
// neighbours, as with the weight on. Oracle: use_normal=off with the colour of those
// pixels NaN instead (also unusable neighbours), at every other pixel.
TEST(ConstantFeatureSkip, NonFinitePixelsOfADroppedPassStayOutOfTheWindows) {
  Frame f = wall_frame(32, 24, 9);
  Frame g = f;
  const int bad[3][2] = {{4, 4}, {10, 11}, {20, 5}};
  for (const auto& b : bad) {
    pass_image(f, Role::Normal).pixel(b[0], b[1])[1] = kNaN;
    for (int c = 0; c < 3; ++c) pass_image(g, Role::Colour).pixel(b[0], b[1])[c] = kNaN;
  }
  const Params p = {{"colour_sigma", 0.5}};
  const Result r = run_filter<BilateralFilter>(f, p);
  Result o = run_filter<BilateralFilter>(g, with(p, {{"use_normal", std::string("off")}}));
  EXPECT_TRUE(has_note(r, "normal pass is constant"));
  for (const auto& b : bad)
    for (int c = 0; c < 3; ++c) o.out.pixel(b[0], b[1])[c] = r.out.pixel(b[0], b[1])[c];
  expect_close(r.out, o.out, 1e-5, "NaN normals");
}

TEST(ConstantFeatureSkip, GuidedLeavesAConstantPassOutOfTheGuide) {
  Frame f = wall_frame(48, 40, 11);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 48; ++x) pass_image(f, Role::Depth).pixel(x, y)[0] = 5.0f + 0.1f * std::sin(0.3f * float(x + y));
  const Result skip = run_filter<GuidedFilter>(f, {{"guide", std::string("normal_depth")}});
  const Result depth = run_filter<GuidedFilter>(f, {{"guide", std::string("depth")}});
  EXPECT_TRUE(has_note(skip, "guided: normal pass is constant over the frame (0.000, 0.000, 1.000): left out of the guide"));
  expect_close(skip.out, depth.out, 1e-5, "normal_depth without the normal");
  EXPECT_GT(changed(skip.out, f.image(Role::Colour)), 0.5);

  // And a constant depth (float rounding) next to a varying normal.
  Frame h = wall_frame(48, 40, 12);
  pass_image(h, Role::Depth) = Image(48, 40, 1, 5.0f);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 48; ++x) {
      float* n = pass_image(h, Role::Normal).pixel(x, y);
      n[0] = 0.5f * std::sin(0.2f * float(x));
      n[2] = std::sqrt(1.0f - n[0] * n[0]);
    }
  pass_image(h, Role::Depth).pixel(3, 3)[0] = 5.0f * (1.0f + 2e-6f);
  const Result skip2 = run_filter<GuidedFilter>(h, {{"guide", std::string("normal_depth")}});
  const Result normal = run_filter<GuidedFilter>(h, {{"guide", std::string("normal")}});
  EXPECT_TRUE(has_note(skip2, "guided: depth pass is constant over the frame (5.000): left out of the guide"));
  expect_close(skip2.out, normal.out, 1e-5, "normal_depth without the depth");
}

// The default guide (normal, depth, colour) takes the passes the render has: a pass it lacks is
// left out as a constant one is (its channel would get coefficient 0), with a note; a guide the
// user chose still needs every pass it names.
TEST(ConstantFeatureSkip, GuidedDefaultGuideLeavesAnAbsentPassOut) {
  Frame h = wall_frame(48, 40, 21);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 48; ++x) {
      float* n = pass_image(h, Role::Normal).pixel(x, y);
      n[0] = 0.5f * std::sin(0.2f * float(x));
      n[2] = std::sqrt(1.0f - n[0] * n[0]);
    }
  const Params chosen = {{"guide", std::string("normal_depth_colour")}};
  const Result constant_depth = run_filter<GuidedFilter>(h, chosen);  // depth 5 everywhere
  const Frame no_depth = without(h, Role::Depth);
  const Result absent = run_filter<GuidedFilter>(no_depth, {});
  EXPECT_TRUE(has_note(absent, "guided: depth pass is absent: left out of the guide"));
  expect_close(absent.out, constant_depth.out, 1e-6, "default guide without a depth pass");
  EXPECT_GT(changed(absent.out, h.image(Role::Colour)), 0.5);

  // Colour alone: the default guide is the colour guide.
  const Frame colour_only = without(without(no_depth, Role::Normal), Role::Albedo);
  const Result bare = run_filter<GuidedFilter>(colour_only, {});
  const Result colour = run_filter<GuidedFilter>(colour_only, {{"guide", std::string("colour")}});
  EXPECT_TRUE(has_note(bare, "guided: normal pass is absent: left out of the guide"));
  expect_close(bare.out, colour.out, 0.0, "default guide on colour alone");

  // A guide the user chose needs its passes.
  GuidedFilter g;
  g.set("guide", std::string("normal_depth_colour"));
  g.commit();
  EXPECT_THROW(g.execute(no_depth), Error);
}

TEST(ConstantFeatureSkip, GuidedKeepsAGuideWhenEveryPassIsConstant) {
  const Frame f = wall_frame(24, 20, 13);
  const Result r = run_filter<GuidedFilter>(f, {{"guide", std::string("normal_depth")}, {"radius", std::int64_t(2)}});
  EXPECT_TRUE(has_note(r, "guided: no guide pass varies over the frame; the depth pass stays"));
  for (float v : r.out.storage()) ASSERT_TRUE(std::isfinite(v));
}

TEST(ConstantFeatureSkip, PwafDropsAConstantNormal) {
  const Frame f = wall_frame(40, 32, 17);
  const Result skip = run_filter<PwafFilter>(f, {});
  const Result none = run_filter<PwafFilter>(without(f, Role::Normal), {});
  EXPECT_TRUE(has_note(skip, "pwaf: normal pass is constant over the frame (0.000, 0.000, 1.000): Gn not used"));
  EXPECT_FALSE(has_note(skip, "position pass is constant"));
  expect_close(skip.out, none.out, 1e-5, "pwaf constant normal");

  Frame nan = f;
  for (float& v : pass_image(nan, Role::Normal).storage()) v = kNaN;
  const Result absent = run_filter<PwafFilter>(nan, {});
  EXPECT_TRUE(has_note(absent, "pwaf: normal pass has no finite value over the frame: Gn not used"));
  expect_close(absent.out, none.out, 1e-5, "pwaf NaN normal");
}

TEST(ConstantFeatureSkip, PwafUsesANormalVaryingJustOverTheTolerance) {
  Frame f = wall_frame(40, 32, 19);
  pass_image(f, Role::Normal).pixel(20, 16)[0] = 0.00041f;  // sigma_n 0.1: tolerance 0.0004
  EXPECT_FALSE(has_note(run_filter<PwafFilter>(f, {}), "normal pass is constant"));
  pass_image(f, Role::Normal).pixel(20, 16)[0] = 0.00039f;
  EXPECT_TRUE(has_note(run_filter<PwafFilter>(f, {}), "normal pass is constant"));
}

// BMFR with epsilon 0: a frame-wide constant normal leaves the normal columns out of
// every block's fit. Oracle: the same frame with the normal changed at one pixel of the
// first block, so the detection keeps it; every other block's normal column is then
// constant, zeroed by the column scaling and dropped by the QR: the same fit there.
TEST(ConstantFeatureSkip, BmfrLeavesAConstantNormalOutOfTheRegression) {
  const int w = 64, h = 48;
  const Frame f = wall_frame(w, h, 23);
  Frame g = f;
  pass_image(g, Role::Normal).pixel(1, 1)[0] = 0.3f;
  auto run = [](const Frame& fr) {
    auto bm = make_filter("bmfr");
    for (const auto& [k, v] : Params{{"epsilon", 0.0}, {"offsets", false}, {"taa", false}, {"block_size", std::int64_t(16)},
                                     {"step_back", false}})  // the regression itself
      bm->set(k, v);
    bm->commit();
    Result r;
    r.out = bm->execute(fr, ExecOptions{});
    r.notes = bm->notes();
    return r;
  };
  const Result skip = run(f), kept = run(g);
  EXPECT_TRUE(has_note(skip, "bmfr: normal pass is constant over the frame (0.000, 0.000, 1.000): left out of the regression"));
  EXPECT_FALSE(has_note(kept, "normal pass is constant"));
  EXPECT_FALSE(has_note(skip, "position pass is constant"));
  int compared = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (x < 16 && y < 16) continue;  // the block holding the changed normal
      for (int c = 0; c < 3; ++c) {
        const float a = skip.out.pixel(x, y)[c], b = kept.out.pixel(x, y)[c];
        ASSERT_NEAR(a, b, 1e-5 * std::max(1.0f, std::fabs(b))) << x << "," << y;
      }
      ++compared;
    }
  EXPECT_EQ(compared, w * h - 256);
}

}  // namespace
}  // namespace mcr
