// Temporal accumulation (BMFR phase I) and reprojection against closed forms on
// synthetic geometry.
#include "temporal/accumulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace mcr {
namespace {

// A plane z = depth seen by a camera whose view is shifted by (sx, sy) pixels: pixel
// (x, y) shows world point (x + sx, y + sy) * 0.01.
struct Geometry {
  Image position, normal, motion;
};

Geometry plane(int w, int h, int sx, int sy, float depth = 1.0f, float vx = 0, float vy = 0) {
  Geometry g{Image(w, h, 3), Image(w, h, 3), Image(w, h, 4)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = g.position.pixel(x, y);
      p[0] = 0.01f * float(x + sx);
      p[1] = 0.01f * float(y + sy);
      p[2] = depth;
      g.normal.pixel(x, y)[2] = 1.0f;
      g.motion.pixel(x, y)[0] = vx;
      g.motion.pixel(x, y)[1] = vy;
    }
  return g;
}

Image noise_image(int w, int h, unsigned seed, float mean = 0.5f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  Image im(w, h, 3);
  for (float& v : im.storage()) v = mean + u(rng);
  return im;
}

TEST(Accumulation, StaticCameraFollowsCumulativeThenExponentialAverage) {
  const int w = 9, h = 7, frames = 14;
  const double alpha = 0.2;
  TemporalAccumulator acc(AccumulationParams{alpha, {}});
  const Geometry g = plane(w, h, 0, 0);
  std::vector<Image> inputs;
  Image want;
  for (int k = 1; k <= frames; ++k) {
    inputs.push_back(noise_image(w, h, unsigned(k)));
    const Image out = acc.accumulate(inputs.back(), g.position, g.normal, &g.motion, 1);
    // Closed form: weight max(1/k, alpha); the switch happens after 1/alpha = 5 frames.
    const double wk = std::max(1.0 / k, alpha);
    if (k == 1) want = inputs.back();
    else
      for (std::size_t i = 0; i < want.storage().size(); ++i)
        want.storage()[i] = float((1 - wk) * want.storage()[i] + wk * inputs.back().storage()[i]);
    for (std::size_t i = 0; i < out.storage().size(); ++i) {
      ASSERT_NEAR(out.storage()[i], want.storage()[i], 1e-5) << "frame " << k;
      if (k <= 5) {  // plain mean of the frames so far
        double m = 0;
        for (const Image& in : inputs) m += in.storage()[i];
        ASSERT_NEAR(out.storage()[i], m / k, 1e-5);
      }
    }
    for (float c : acc.sample_count()) ASSERT_EQ(c, float(k));
    EXPECT_FALSE(acc.last_reprojection().cut);
  }
  // Converges towards the mean (0.5) of the noisy frames: the EMA keeps a residual
  // variance of alpha / (2 - alpha) times the per-frame variance (1/12).
  double se = 0;
  const Image& last = acc.accumulate(noise_image(w, h, 99), g.position, g.normal, &g.motion, 1);
  for (float v : last.storage()) se += (v - 0.5) * (v - 0.5);
  EXPECT_LT(se / double(last.storage().size()), 3 * (alpha / (2 - alpha)) / 12.0);
}

TEST(Accumulation, IntegerTranslationReprojectsExactly) {
  // The camera moves so that pixel (x, y) saw its world point at (x + 2, y + 1) in the
  // previous frame: Vector = previous minus current with Y up, so (2, -1).
  const int w = 12, h = 10;
  TemporalAccumulator acc;
  const Geometry g1 = plane(w, h, 0, 0);
  const Geometry g2 = plane(w, h, 2, 1, 1.0f, 2.0f, -1.0f);
  // World texture T(X, Y) seen by both frames; frame 2 adds 1.
  auto texture = [](int X, int Y) { return float((X * 7 + Y * 13) % 11) / 11.0f; };
  Image c1(w, h, 3), c2(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        c1.at(x, y, c) = texture(x, y) + float(c);
        c2.at(x, y, c) = texture(x + 2, y + 1) + float(c) + 1.0f;
      }
  acc.accumulate(c1, g1.position, g1.normal, &g1.motion, 2);
  const Image out = acc.accumulate(c2, g2.position, g2.normal, &g2.motion, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool inside = x + 2 < w && y + 1 < h;
      for (int c = 0; c < 3; ++c) {
        const float want = inside ? c2.at(x, y, c) - 0.5f : c2.at(x, y, c);  // mean of the two, or new
        ASSERT_NEAR(out.at(x, y, c), want, 1e-6) << x << "," << y;
      }
      EXPECT_EQ(acc.sample_count()[std::size_t(y * w + x)], inside ? 2.0f : 1.0f);
    }
}

TEST(Accumulation, DisocclusionDiscardsHistory) {
  const int w = 16, h = 16;
  TemporalAccumulator acc;
  const Geometry g1 = plane(w, h, 0, 0);
  Geometry g2 = plane(w, h, 0, 0);
  // An object appears in the top-left quarter (position jump) and a patch turns (normal).
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) g2.position.pixel(x, y)[2] = 0.5f;
  for (int y = 10; y < 14; ++y)
    for (int x = 10; x < 14; ++x) {
      float* n = g2.normal.pixel(x, y);
      n[0] = 1.0f;
      n[2] = 0.0f;
    }
  const Image a(w, h, 3, 1.0f), b(w, h, 3, 3.0f);
  acc.accumulate(a, g1.position, g1.normal, &g1.motion);
  const Image out = acc.accumulate(b, g2.position, g2.normal, &g2.motion);
  EXPECT_FALSE(acc.last_reprojection().cut);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool fresh = (x < 8 && y < 8) || (x >= 10 && x < 14 && y >= 10 && y < 14);
      EXPECT_FLOAT_EQ(out.at(x, y, 0), fresh ? 3.0f : 2.0f) << x << "," << y;
    }
}

TEST(Accumulation, CameraCutResetsHistory) {
  const int w = 20, h = 10;
  TemporalAccumulator acc;
  const Geometry g1 = plane(w, h, 0, 0);
  const Geometry g2 = plane(w, h, 0, 0, 7.0f);  // everything moved: a cut
  acc.accumulate(Image(w, h, 3, 1.0f), g1.position, g1.normal, &g1.motion);
  acc.accumulate(Image(w, h, 3, 1.0f), g1.position, g1.normal, &g1.motion);
  const Image out = acc.accumulate(Image(w, h, 3, 5.0f), g2.position, g2.normal, &g2.motion);
  EXPECT_TRUE(acc.last_reprojection().cut);
  for (float v : out.storage()) EXPECT_EQ(v, 5.0f);
  for (float c : acc.sample_count()) EXPECT_EQ(c, 1.0f);
  // Half of the frame changing is not a cut.
  Geometry g3 = g2;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w / 2; ++x) g3.position.pixel(x, y)[2] = 9.0f;
  acc.accumulate(Image(w, h, 3, 5.0f), g3.position, g3.normal, &g3.motion);
  EXPECT_FALSE(acc.last_reprojection().cut);
  // A size change drops the history too.
  const Geometry g4 = plane(w + 1, h, 0, 0);
  const Image out4 = acc.accumulate(Image(w + 1, h, 3, 2.0f), g4.position, g4.normal, &g4.motion);
  EXPECT_FALSE(acc.last_reprojection().has_history);
  for (float v : out4.storage()) EXPECT_EQ(v, 2.0f);
}

TEST(Accumulation, NonFiniteSamplesKeepHistory) {
  const int w = 4, h = 4;
  TemporalAccumulator acc;
  const Geometry g = plane(w, h, 0, 0);
  Image c(w, h, 3, 2.0f);
  c.at(1, 1, 0) = std::numeric_limits<float>::quiet_NaN();
  Image out = acc.accumulate(c, g.position, g.normal, &g.motion);
  EXPECT_EQ(acc.sample_count()[5], 0.0f);  // invalid: no history yet
  EXPECT_EQ(out.at(1, 1, 0), 0.0f);
  Image d(w, h, 3, 4.0f);
  out = acc.accumulate(d, g.position, g.normal, &g.motion);
  EXPECT_EQ(out.at(1, 1, 0), 4.0f);  // the invalid history tap was not read
  EXPECT_EQ(out.at(0, 0, 0), 3.0f);
  d.at(2, 2, 1) = std::numeric_limits<float>::infinity();
  out = acc.accumulate(d, g.position, g.normal, &g.motion);
  EXPECT_NEAR(out.at(2, 2, 1), 3.0f, 1e-6);  // kept history, count unchanged
  EXPECT_EQ(acc.sample_count()[10], 2.0f);
  for (float v : out.storage()) EXPECT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace mcr
