// prepare/empty_pixels: where nothing was rendered (alpha 0, colour 0) every filter writes 0.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "prepare/empty_pixels.h"

namespace mcr {
namespace {

// Left: a noisy object (alpha 1); right: the transparent world (alpha 0, colour 0), but for one
// column of emission over it (alpha 0, colour 2). Oracle: the same frame without its alpha pass,
// whose result differs only where the rule applies.
Frame transparent_frame(int w, int h, bool with_alpha) {
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.2f);
  Image colour(w, h, 3), alpha(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool object = x < w / 2, glow = x == w - 4;
      alpha.at(x, y, 0) = object ? 1.0f : 0.0f;
      for (int c = 0; c < 3; ++c) colour.at(x, y, c) = object ? 0.6f + noise(rng) : glow ? 2.0f : 0.0f;
    }
  Frame f = testutil::colour_frame(colour);
  if (with_alpha) testutil::add_pass(f, Role::Alpha, alpha);
  return f;
}

TEST(EmptyPixels, EveryFilterLeavesNothingWhereNothingWasRendered) {
  const int w = 40, h = 24;
  const Frame plain = transparent_frame(w, h, false), transparent = transparent_frame(w, h, true);
  for (const char* name : {"box", "gaussian", "bilateral", "atrous", "guided", "pwaf"}) {
    SCOPED_TRACE(name);
    auto a = make_filter(name), b = make_filter(name);
    if (std::string(name) == "guided") {  // no feature passes here: the self-guided case
      a->set("guide", std::string("luminance"));
      b->set("guide", std::string("luminance"));
    }
    a->commit();
    b->commit();
    const Image without = a->execute(plain), with = b->execute(transparent);
    int leaked = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) {
          const bool empty = x >= w / 2 && x != w - 4;
          if (empty) {
            EXPECT_EQ(with.at(x, y, c), 0.0f) << x << "," << y;
            leaked += without.at(x, y, c) != 0.0f;
          } else {
            EXPECT_EQ(with.at(x, y, c), without.at(x, y, c)) << x << "," << y;  // the object, the emission
          }
        }
    if (std::string(name) == "gaussian") EXPECT_GT(leaked, 0);  // the rule has something to do
  }
}

TEST(EmptyPixels, OnlyExactZerosOfBothCount) {
  Image alpha(3, 1, 1), input(3, 1, 3), out(3, 1, 3, 0.5f);
  alpha.at(1, 0, 0) = 1e-7f;     // covered a little
  input.at(2, 0, 1) = -0.0f;     // negative zero is zero
  EXPECT_EQ(keep_empty_pixels(alpha, input, Roi::all(3, 1), out), 2u);
  EXPECT_EQ(out.at(0, 0, 0), 0.0f);
  EXPECT_EQ(out.at(1, 0, 0), 0.5f);
  EXPECT_EQ(out.at(2, 0, 2), 0.0f);
  Image small(2, 1, 1);
  EXPECT_EQ(keep_empty_pixels(small, input, Roi::all(3, 1), out), 0u);  // sizes differ: nothing
}

}  // namespace
}  // namespace mcr
