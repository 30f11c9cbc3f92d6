// The history guards (issue 15): the sample limits and neighbourhood caps against the
// rules written out pixel by pixel, the accumulation's guards against their closed form
// and alike on every instruction set, and the surface classes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "image/luminance.h"
#include "image/pass.h"
#include "pass_testutil.h"
#include "prepare/history_guards.h"
#include "prepare/sample_limits.h"
#include "prepare/surface_classes.h"
#include "temporal/accumulation.h"
#include "util/isa.h"

namespace mcr {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

Image noisy(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Image im(w, h, 3);
  for (float& v : im.storage()) v = u(rng);
  return im;
}

// The limit of one pixel, as the header states it: other finite pixels of the window.
double brute_limit(const Image& im, int x, int y, int r, double k) {
  double s = 0, n = 0;
  for (int qy = std::max(0, y - r); qy <= std::min(im.height() - 1, y + r); ++qy)
    for (int qx = std::max(0, x - r); qx <= std::min(im.width() - 1, x + r); ++qx)
      if ((qx != x || qy != y) && finite3(im.pixel(qx, qy))) {
        s += luminance(im.pixel(qx, qy));
        n += 1;
      }
  if (n < 3) return kInf;
  const double mu = s / n;
  double v = 0;
  for (int qy = std::max(0, y - r); qy <= std::min(im.height() - 1, y + r); ++qy)
    for (int qx = std::max(0, x - r); qx <= std::min(im.width() - 1, x + r); ++qx)
      if ((qx != x || qy != y) && finite3(im.pixel(qx, qy))) v += (luminance(im.pixel(qx, qy)) - mu) * (luminance(im.pixel(qx, qy)) - mu);
  return mu + std::max(k * std::sqrt(v / n), 0.01 * std::fabs(mu));
}

TEST(SampleLimits, EveryPixelFollowsTheRuleWrittenOut) {
  Image im = noisy(23, 17, 3);
  im.at(5, 5, 1) = 1e30f;  // a firefly that dwarfs its window's sums
  im.at(6, 5, 0) = 300.0f;
  im.at(12, 9, 2) = std::numeric_limits<float>::quiet_NaN();
  im.at(0, 16, 0) = kInf;
  for (int r : {1, 2, 3}) {
    std::vector<float> lim;
    firefly_limits(im, r, 3.0, 2, lim);
    for (int y = 0; y < im.height(); ++y)
      for (int x = 0; x < im.width(); ++x) {
        const double want = brute_limit(im, x, y, r, 3.0);
        const float got = lim[std::size_t(y) * std::size_t(im.width()) + std::size_t(x)];
        SCOPED_TRACE("r " + std::to_string(r) + " at " + std::to_string(x) + "," + std::to_string(y));
        if (std::isinf(want)) {
          EXPECT_TRUE(std::isinf(got));
          continue;
        }
        const double bound = std::min(want, double(std::numeric_limits<float>::max()));
        ASSERT_NEAR(got, bound, 1e-3 * std::fabs(bound) + 1e-6);  // float sums (the header's promise)
      }
  }
}

TEST(SampleLimits, NeighbourhoodCapsAreTheBrightestOfTheFlaggedPixels3x3) {
  Image im = noisy(9, 8, 5);
  im.at(4, 4, 1) = 50.0f;
  std::vector<std::uint8_t> flags(72, 0);
  for (int i = 0; i < 72; i += 3) flags[std::size_t(i)] = 2;
  std::vector<float> cap;
  neighbourhood_caps(im, flags, 2, 1, cap);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 9; ++x) {
      const std::size_t i = std::size_t(y) * 9 + std::size_t(x);
      if (!flags[i]) {
        EXPECT_TRUE(std::isinf(cap[i]));
        continue;
      }
      double m = -1e300;
      for (int qy = std::max(0, y - 1); qy <= std::min(7, y + 1); ++qy)
        for (int qx = std::max(0, x - 1); qx <= std::min(8, x + 1); ++qx) m = std::max(m, luminance(im.pixel(qx, qy)));
      EXPECT_FLOAT_EQ(cap[i], float(m));
    }
}

// A static shot: every pixel reprojects onto itself (all four bilinear taps kept at
// integer positions, so the history is the pixel's own).
struct StaticShot {
  Image position, normal;
  explicit StaticShot(int w, int h) : position(w, h, 3), normal(w, h, 3) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        position.at(x, y, 0) = 0.01f * float(x);
        position.at(x, y, 1) = 0.01f * float(y);
        position.at(x, y, 2) = 1.0f;
        normal.at(x, y, 2) = 1.0f;
      }
  }
};

Image flat(int w, int h, float v) { return Image(w, h, 3, v); }

TEST(AccumulationGuards, AFireflyIsCutUnlessItsHistoryBacksIt) {
  const int w = 7, h = 6;
  StaticShot s(w, h);
  std::vector<float> lim(std::size_t(w) * h, 2.0f);
  AccumulationGuards g;
  g.limit = lim.data();
  g.history_factor = 4.0f;
  // No history: a sample of luminance 30 is cut to 2, its colour ratios kept.
  TemporalAccumulator acc(AccumulationParams{0.2, {}});
  acc.set_guards(g);
  Image first = flat(w, h, 0.5f);
  first.at(3, 3, 0) = 30.0f;
  first.at(3, 3, 1) = 30.0f;
  first.at(3, 3, 2) = 30.0f;
  const Image& a = acc.accumulate(first, s.position, s.normal, nullptr, 1);
  EXPECT_NEAR(a.at(3, 3, 0), 2.0f, 1e-5);
  EXPECT_NEAR(a.at(3, 3, 1), 2.0f, 1e-5);
  EXPECT_EQ(a.at(2, 3, 0), 0.5f);  // below the limit: untouched
  // A history of 2 backs up to 4 x 2 = 8: a sample of 30 is cut to 8, then blended 1/2.
  Image second = first;
  const Image& b = acc.accumulate(second, s.position, s.normal, nullptr, 1);
  EXPECT_NEAR(b.at(3, 3, 0), 0.5f * (2.0f + 8.0f), 1e-5);
  // A pixel without history takes limit_fresh when given.
  std::vector<float> fresh(std::size_t(w) * h, 6.0f);
  g.limit_fresh = fresh.data();
  TemporalAccumulator acc2(AccumulationParams{0.2, {}});
  acc2.set_guards(g);
  EXPECT_NEAR(acc2.accumulate(first, s.position, s.normal, nullptr, 1).at(3, 3, 0), 6.0f, 1e-5);
  // A sample within 4x its history passes whole.
  Image third = flat(w, h, 0.5f);
  third.at(3, 3, 0) = third.at(3, 3, 1) = third.at(3, 3, 2) = 12.0f;  // history 5: bound 20
  const Image& c = acc.accumulate(third, s.position, s.normal, nullptr, 1);
  EXPECT_NEAR(c.at(3, 3, 0), 5.0f + (12.0f - 5.0f) / 3.0f, 1e-4);
}

TEST(AccumulationGuards, AMirrorKeepsAShortHistoryCutToItsNeighbourhood) {
  const int w = 5, h = 5;
  StaticShot s(w, h);
  std::vector<float> afl(std::size_t(w) * h, 0.0f), cap(std::size_t(w) * h, kInf);
  afl[12] = 0.5f;
  cap[12] = 1.0f;  // the current neighbourhood backs at most 1
  AccumulationGuards g;
  g.alpha_floor = afl.data();
  g.history_cap = cap.data();
  TemporalAccumulator acc(AccumulationParams{0.2, {}});
  for (int k = 0; k < 8; ++k) acc.accumulate(flat(w, h, 10.0f), s.position, s.normal, nullptr, 1);  // a bright past
  acc.set_guards(g);
  const Image& out = acc.accumulate(flat(w, h, 0.2f), s.position, s.normal, nullptr, 1);
  // The mirror: history 10 cut to 1, then the new 0.2 at weight 0.5.
  EXPECT_NEAR(out.at(2, 2, 0), 0.5f * (1.0f + 0.2f), 1e-5);
  // Its neighbours: the plain exponential average (weight 0.2).
  EXPECT_NEAR(out.at(1, 2, 0), 10.0f + 0.2f * (0.2f - 10.0f), 1e-4);
}

TEST(AccumulationGuards, EveryInstructionSetGivesTheSameBits) {
  const int w = 37, h = 11;  // rows longer than 8 pixels with a scalar tail
  StaticShot s(w, h);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 3.0f);
  std::vector<float> lim(std::size_t(w) * h), fresh(lim.size()), afl(lim.size()), cap(lim.size());
  for (std::size_t i = 0; i < lim.size(); ++i) {
    lim[i] = i % 5 == 0 ? kInf : u(rng);
    fresh[i] = 2.0f * lim[i];
    afl[i] = i % 3 == 0 ? 0.7f : 0.0f;
    cap[i] = i % 4 == 0 ? u(rng) : kInf;
  }
  AccumulationGuards g{lim.data(), fresh.data(), afl.data(), cap.data(), 2.5f};
  std::vector<Image> outs;
  for (Isa level : {Isa::Generic, best_isa()}) {
    const ScopedIsa use(level);
    TemporalAccumulator acc(AccumulationParams{0.2, {}});
    acc.set_guards(g);
    Image last;
    for (unsigned k = 0; k < 4; ++k) {
      Image in = noisy(w, h, 11 + k);
      for (float& v : in.storage()) v *= (k % 2 ? 4.0f : 1.0f);
      last = acc.accumulate(in, s.position, s.normal, nullptr, 1);
    }
    outs.push_back(last);
  }
  ASSERT_EQ(outs[0].storage().size(), outs[1].storage().size());
  for (std::size_t i = 0; i < outs[0].storage().size(); ++i) ASSERT_EQ(outs[0].storage()[i], outs[1].storage()[i]) << i;
}

TEST(SurfaceClasses, LightInTheAlbedoAndMirrorsFromTheColourPasses) {
  Frame f;
  f.width = 4;
  f.height = 1;
  Image albedo(4, 1, 3, 0.5f), diffuse(4, 1, 3, 0.6f), glossy(4, 1, 3, 1.0f);
  albedo.at(0, 0, 1) = 200.0f;                                      // holds light
  for (int c = 0; c < 3; ++c) diffuse.at(1, 0, c) = 0.0f;           // a metal
  for (int c = 0; c < 3; ++c) diffuse.at(2, 0, c) = 0.05f;          // gloss 20x diffuse: mirror-like
  f.passes = {testutil::make_pass(Role::Colour, "Combined", Image(4, 1, 3, 1.0f)),
              testutil::make_pass(Role::Albedo, "Denoising Albedo", albedo)};
  SurfaceClasses sc;
  classify_surfaces(f, 1, sc);
  EXPECT_FALSE(sc.colour_passes);
  EXPECT_EQ(sc.flags, (std::vector<std::uint8_t>{1, 0, 0, 0}));
  f.passes.push_back(testutil::make_pass(Role::DiffuseColour, "DiffCol", diffuse));
  f.passes.push_back(testutil::make_pass(Role::GlossyColour, "GlossCol", glossy));
  classify_surfaces(f, 1, sc);
  EXPECT_TRUE(sc.colour_passes);
  EXPECT_EQ(sc.flags, (std::vector<std::uint8_t>{1, 2, 2, 0}));
  EXPECT_EQ(sc.light_in_albedo, 1u);
  EXPECT_EQ(sc.mirror, 2u);
}

TEST(SurfaceClasses, TheWorldBehindEverythingHasANormalOfZero) {
  Frame f;
  f.width = 4;
  f.height = 1;
  Image normal(4, 1, 3, 0.0f);
  normal.at(1, 0, 2) = 1.0f;                                          // a surface
  normal.at(2, 0, 0) = std::numeric_limits<float>::quiet_NaN();      // unknown: not background
  f.passes = {testutil::make_pass(Role::Colour, "Combined", Image(4, 1, 3, 1.0f)),
              testutil::make_pass(Role::Normal, "Normal", normal, Space::World)};
  SurfaceClasses sc;
  classify_surfaces(f, 1, sc);
  EXPECT_EQ(sc.flags, (std::vector<std::uint8_t>{4, 0, 0, 4}));
  EXPECT_EQ(sc.background, 2u);
  EXPECT_FALSE(sc.any());  // nothing bmfr keeps out of its fit
}

// Blender's world has normal and position 0 and no motion: its history is reprojected in
// place. Under a moving camera an environment's bright spot leaves a pixel; the guards cut
// that pixel's history to its current 3x3 neighbourhood (closed form), which the plain
// average would keep at 10 x 0.8 + 0.2 x 0.3.
TEST(HistoryGuards, ABackgroundsHistoryIsNoBrighterThanItsNeighbourhood) {
  const int w = 7, h = 5;
  const Image zero(w, h, 3, 0.0f);
  Frame f;
  f.width = w;
  f.height = h;
  f.passes = {testutil::make_pass(Role::Normal, "Normal", zero, Space::World)};
  SurfaceClasses sc;
  classify_surfaces(f, 1, sc);
  ASSERT_EQ(sc.background, std::size_t(w) * h);
  Image spot = flat(w, h, 0.3f);
  for (int c = 0; c < 3; ++c) spot.at(3, 2, c) = 10.0f;
  const Image now = flat(w, h, 0.3f);  // the spot has left
  for (bool cap : {true, false}) {
    SCOPED_TRACE(cap);
    TemporalAccumulator acc(AccumulationParams{0.2, {}});
    for (int k = 0; k < 8; ++k) acc.accumulate(spot, zero, zero, nullptr, 1);
    const double history = acc.accumulate(spot, zero, zero, nullptr, 1).at(3, 2, 0);
    HistoryGuardSettings hs;
    hs.limit_k = 0;  // the background rule alone
    hs.background_cap = cap;
    HistoryGuards guards;
    acc.set_guards(guards.build(now, sc, hs, 1));
    const Image& out = acc.accumulate(now, zero, zero, nullptr, 1);
    EXPECT_NEAR(out.at(3, 2, 0), cap ? 0.3 : 0.8 * history + 0.2 * 0.3, 1e-4);
    EXPECT_NEAR(out.at(0, 0, 0), 0.3, 1e-6);  // where nothing moved, the same either way
  }
}

}  // namespace
}  // namespace mcr
