// The residual shrink (kernels/residual_shrink.h; bmfr's detail stage): the window's mean
// residual added back with the James-Stein weight. Oracles: closed forms for a step in the residual (the
// window's mean and variance of a two-valued residual written out), the expected size of the
// shrunk mean of pure noise, and a hard shadow on a flat wall through the whole filter.
#include "kernels/residual_shrink.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "filters/registry.h"
#include "floor_frame_testutil.h"

namespace mcr {
namespace {

thread_local std::vector<float> scratch;  // the window sums' planes, as bmfr keeps them

constexpr int kW = 24, kH = 10, kEdge = 12;
constexpr double kA = 0.75;  // the step's height

// A planar result (three planes) that varies per pixel, and the accumulation that lies kA
// above it left of kEdge and on it right of it, divided by `albedo`.
struct Step {
  std::vector<float> result;
  Image accumulated, albedo;
};

Step step(float albedo) {
  Step s{std::vector<float>(std::size_t(kW) * kH * 3), Image(kW, kH, 3), Image(kW, kH, 3, albedo)};
  const std::size_t n = std::size_t(kW) * kH;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) {
        const float r = 0.5f + 0.01f * float(x) + 0.02f * float(y) + 0.1f * float(c);
        s.result[std::size_t(c) * n + std::size_t(y) * kW + std::size_t(x)] = r;
        s.accumulated.at(x, y, c) = float((double(r) + (x < kEdge ? kA : 0.0)) / albedo);
      }
  return s;
}

// Closed form at (x, y): the window holds rows * cols pixels, j of its columns left of the
// edge, so the residual's mean is kA j / cols and its variance kA^2 p (1 - p), p = j / cols:
// w = 1 - k (1 - p) / (n p), clamped to [0, 1].
double expected_addition(int x, int y, const ResidualSettings& rs, const Roi& roi = Roi::all(kW, kH)) {
  if (!roi.contains(x, y)) return 0.0;
  const int x0 = std::max(roi.x0, x - rs.radius), x1 = std::min(roi.x1 - 1, x + rs.radius);
  const int y0 = std::max(roi.y0, y - rs.radius), y1 = std::min(roi.y1 - 1, y + rs.radius);
  const int cols = x1 - x0 + 1, rows = y1 - y0 + 1;
  int j = 0;
  for (int q = x0; q <= x1; ++q) j += q < kEdge;
  if (j == 0) return 0.0;
  const double p = double(j) / cols, n = double(rows) * cols;
  const double w = std::clamp(1.0 - rs.k * (1.0 - p) / (n * p), 0.0, 1.0);
  return w * kA * p;
}

void expect_step_oracle(const Step& s, const std::vector<float>& before, const ResidualSettings& rs,
                        const Roi& roi = Roi::all(kW, kH)) {
  const std::size_t n = std::size_t(kW) * kH;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c) {
        const std::size_t i = std::size_t(c) * n + std::size_t(y) * kW + std::size_t(x);
        ASSERT_NEAR(double(s.result[i]) - before[i], expected_addition(x, y, rs, roi), 1e-5) << x << "," << y << " c" << c;
      }
}

TEST(ResidualShrink, AStepInTheResidualComesBackAsItsShrunkWindowMean) {
  for (int radius : {1, 2}) {
    SCOPED_TRACE(radius);
    Step s = step(1.0f);
    const std::vector<float> before = s.result;
    ResidualSettings rs;
    rs.radius = radius;
    add_back_residual(rs, s.accumulated, nullptr, {s.result.data(), 1, std::size_t(kW) * kH}, Roi::all(kW, kH), scratch, 1);
    expect_step_oracle(s, before, rs);
    // Deep inside the step the whole residual comes back; past the window, nothing.
    EXPECT_NEAR(s.result[0] - before[0], kA, 1e-6);
    EXPECT_EQ(s.result[kW - 1], before[kW - 1]);
    // The same result held interleaved (as the light-field filters hold theirs).
    const std::size_t n = std::size_t(kW) * kH;
    std::vector<float> inter(n * 3);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < 3; ++c) inter[i * 3 + c] = before[c * n + i];
    add_back_residual(rs, s.accumulated, nullptr, {inter.data(), 3, 1}, Roi::all(kW, kH), scratch, 2);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < 3; ++c) ASSERT_EQ(inter[i * 3 + c], s.result[c * n + i]) << i << " c" << c;
  }
}

TEST(ResidualShrink, OnlyTheRoiIsReadAndChanged) {
  // A region across the step: windows end at its border, nothing outside moves.
  Step s = step(1.0f);
  const std::vector<float> before = s.result;
  const Roi roi{3, 2, 17, 8};
  ResidualSettings rs;
  add_back_residual(rs, s.accumulated, nullptr, {s.result.data(), 1, std::size_t(kW) * kH}, roi, scratch, 1);
  expect_step_oracle(s, before, rs, roi);
}

TEST(ResidualShrink, WithAnAlbedoTheResidualIsOfTheRemodulatedAccumulation) {
  Step s = step(2.5f);
  const std::vector<float> before = s.result;
  ResidualSettings rs;
  const std::size_t taken =
      add_back_residual(rs, s.accumulated, &s.albedo, {s.result.data(), 1, std::size_t(kW) * kH}, Roi::all(kW, kH),
                        scratch, 2);
  expect_step_oracle(s, before, rs);
  EXPECT_GT(taken, std::size_t(kH * (kEdge - 2)));
}

TEST(ResidualShrink, NoiseAboutARightFitAddsLittle) {
  // Pure noise (sigma 1, channels independent) about the result: the window mean of 25 has
  // deviation 0.2, added whole (k = 0) its RMS is 0.2. Shrunk (k = 3) a pixel takes some
  // only where 25 m_l^2 > 3 v_l: m_l (the mean over R, G, B) has variance 1/75, so where a
  // chi^2_1 variable exceeds 9 (0.3% of the pixels), and then only in part.
  const int w = 160, h = 120;
  const std::size_t n = std::size_t(w) * h;
  std::mt19937 rng(7);
  std::normal_distribution<float> g(0.0f, 1.0f);
  Image acc(w, h, 3);
  for (float& v : acc.storage()) v = g(rng);
  auto rms_of_addition = [&](double k) {
    std::vector<float> result(n * 3, 0.0f);
    ResidualSettings rs;
    rs.k = k;
    add_back_residual(rs, acc, nullptr, {result.data(), 1, n}, Roi::all(w, h), scratch, 2);
    double s2 = 0;
    for (float v : result) s2 += double(v) * v;
    return std::sqrt(s2 / double(result.size()));
  };
  EXPECT_NEAR(rms_of_addition(0.0), 0.2, 0.02);
  EXPECT_LT(rms_of_addition(3.0), 0.01);
}

TEST(ResidualShrink, NonFiniteResidualsTakeNoPart) {
  Step s = step(1.0f);
  const std::vector<float> before = s.result;
  s.accumulated.at(3, 4, 1) = std::numeric_limits<float>::quiet_NaN();
  s.accumulated.at(5, 2, 0) = std::numeric_limits<float>::infinity();
  add_back_residual({}, s.accumulated, nullptr, {s.result.data(), 1, std::size_t(kW) * kH}, Roi::all(kW, kH), scratch, 1);
  const std::size_t n = std::size_t(kW) * kH;
  // Left of the edge every finite window residual is kA: v = 0, so kA comes back whole,
  // next to the two bad pixels and on them.
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x + 2 < kEdge; ++x)
      for (int c = 0; c < 3; ++c) {
        const std::size_t i = std::size_t(c) * n + std::size_t(y) * kW + std::size_t(x);
        ASSERT_TRUE(std::isfinite(s.result[i]));
        ASSERT_NEAR(double(s.result[i]) - before[i], kA, 1e-5) << x << "," << y;
      }
}

// A flat wall lit 1.0 with a hard shadow band (8 pixels wide, 0.2) that no feature tells
// apart, noise free, a static camera: the fit spreads the band over its block; the detail
// stage brings it back.
TEST(BmfrDetail, AHardShadowOnAFlatWallComesBack) {
  const int w = 64, h = 32, band0 = 28, band1 = 36;
  Image colour(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) colour.at(x, y, c) = x >= band0 && x < band1 ? 0.2f : 1.0f;
  const Frame f = testutil::floor_frame(colour, Image(w, h, 3, 1.0f));
  auto worst_in_band = [&](double k) {
    auto b = make_filter("bmfr");
    b->set("residual_k", k);
    b->set("block_size", std::int64_t(32));
    b->commit();
    Image out;
    for (int frame = 0; frame < 4; ++frame) out = b->execute(f);
    double e = 0;
    for (int y = 0; y < h; ++y)
      for (int x = band0 + 2; x < band1 - 2; ++x) e = std::max(e, std::fabs(double(out.at(x, y, 1)) - 0.2));
    return e;
  };
  EXPECT_GT(worst_in_band(0.0), 0.3);   // the fit alone loses the shadow
  EXPECT_LT(worst_in_band(3.0), 0.03);  // the default brings it back
}

}  // namespace
}  // namespace mcr
