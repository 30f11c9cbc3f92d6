// bmfr on highlights and mirrors (issue 15): a pixel whose albedo flips between 200 and
// 0.4 must not light its block, and a reflection that slides away must not trail.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "filters/registry.h"
#include "floor_frame_testutil.h"

namespace mcr {
namespace {

using testutil::floor_frame;
using testutil::make_pass;

std::unique_ptr<Filter> bmfr(std::initializer_list<std::pair<const char*, ParamValue>> params = {}) {
  auto f = make_filter("bmfr");
  for (const auto& kv : params) f->set(kv.first, kv.second);
  f->commit();
  return f;
}

void set_rgb(Image& im, int x, int y, float v) {
  for (int c = 0; c < 3; ++c) im.at(x, y, c) = v;
}

// Frame k of a textured floor under light 1 (colour = albedo), with one pixel on a mirror
// bounce to the sun: even frames its sample hit the sun through the bounce (albedo 200,
// colour 120), odd frames the colour did and the albedo did not (albedo 0.4, colour 100).
Frame flip_frame(int k, bool colour_passes) {
  const int w = 32, h = 32;
  Image albedo(w, h, 3), colour(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float a = ((x / 4 + y / 4) % 2) ? 0.4f : 0.7f;
      set_rgb(albedo, x, y, a);
      set_rgb(colour, x, y, a);
    }
  set_rgb(albedo, 13, 14, k % 2 ? 0.4f : 200.0f);
  set_rgb(colour, 13, 14, k % 2 ? 100.0f : 120.0f);
  return floor_frame(colour, albedo, colour_passes, 0.5f);
}

TEST(BmfrHighlights, AnAlbedoThatFlipsBetween200And04DoesNotLightItsBlock) {
  auto f = bmfr();
  Image out;
  for (int k = 0; k < 8; ++k) out = f->execute(flip_frame(k, true));
  const Frame last = flip_frame(7, true);
  const Image& truth = last.image(Role::Albedo);  // light 1: every other pixel's colour is its albedo
  double worst = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      if (x == 13 && y == 14) continue;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(double(out.at(x, y, c)) / truth.at(x, y, c) - 1.0));
    }
  EXPECT_LT(worst, 0.1) << "the highlight's light spread over its block";
  // The pixel itself: never brighter than anything it was given (remodulation by 200 of
  // a neighbour's illumination would be).
  for (int c = 0; c < 3; ++c) EXPECT_LE(out.at(13, 14, c), 120.0f);
}

// A mirror floor (Diffuse Color 0) reflecting a bright 2x2 spot: frames 0-5 at (8, 8),
// then at (20, 8). The surface does not move; its reflection does.
Frame mirror_frame(int k, bool colour_passes) {
  const int w = 32, h = 20;
  Image colour(w, h, 3, 0.3f), albedo(w, h, 3, 0.5f);
  const int sx = k < 6 ? 8 : 20;
  for (int y = 8; y < 10; ++y)
    for (int x = sx; x < sx + 2; ++x) set_rgb(colour, x, y, 20.0f);
  return floor_frame(colour, albedo, colour_passes, 0.0f);
}

TEST(BmfrHighlights, AReflectionThatSlidesAwayDoesNotTrail) {
  for (bool colour_passes : {true, false}) {
    auto f = bmfr();
    Image out;
    for (int k = 0; k < 8; ++k) out = f->execute(mirror_frame(k, colour_passes));
    // Two frames after the spot left (8, 8): back to the floor's 0.3 when bmfr knows it
    // is a mirror; without the colour passes the history still holds the spot there.
    double left = 0;
    for (int y = 8; y < 10; ++y)
      for (int x = 8; x < 10; ++x) left = std::max(left, double(out.at(x, y, 1)));
    if (colour_passes) {
      EXPECT_LT(left, 0.6) << "trail of the reflection on a mirror";
      EXPECT_GT(out.at(20, 8, 1), 10.0f) << "the reflection where it is now";
    } else {
      EXPECT_GT(left, 1.0) << "without Diffuse/Glossy Color the history is trusted (what the guard is for)";
    }
  }
}

TEST(BmfrHighlights, OnlyAFrameWithoutHistoryStepsBack) {
  // A still is a spatial estimate: the step back guards it as every image filter's. A
  // frame built from history is not (its limits assume this frame's local range).
  auto f = bmfr();
  auto stepped = [&] {
    for (const std::string& n : f->notes())
      if (n.rfind("step_back:", 0) == 0) return true;
    return false;
  };
  f->execute(flip_frame(0, true));
  EXPECT_TRUE(stepped());
  f->execute(flip_frame(1, true));
  EXPECT_FALSE(stepped());
  f->reset();
  f->execute(flip_frame(2, true));
  EXPECT_TRUE(stepped());
}

}  // namespace
}  // namespace mcr
