// The report's derived figures against closed forms: "worth N x samples" on renders whose
// relMSE is an exact power of spp, Pareto fronts against their definition checked pair by pair,
// the scaling slope of a known power law.
#include <gtest/gtest.h>

#include <cmath>

#include "report/report_math.h"
#include "report/scaling.h"

namespace mcr {

TEST(ReportWorth, PowerLawLevelsGiveTheExactSampleRatio) {
  // relMSE = 2 / spp^1.5 at 1, 4, 16, 64 spp: a run at relMSE r is worth (2/r)^(1/1.5) spp.
  std::vector<std::pair<int, double>> levels;
  for (int n : {1, 4, 16, 64}) levels.push_back({n, 2.0 / std::pow(n, 1.5)});
  for (double spp : {2.0, 10.0, 16.0, 40.0, 64.0, 300.0, 0.5}) {  // inside, at and beyond the levels
    const double r = 2.0 / std::pow(spp, 1.5);
    EXPECT_NEAR(worth_x_samples(levels, 16, r), spp / 16, 1e-9 * spp) << spp;
  }
}

TEST(ReportWorth, PiecewiseBetweenLevelsThatBend) {
  // 1 -> 4 spp: relMSE 1 -> 0.25 (slope -1); 4 -> 16: 0.25 -> 0.125 (slope -0.5).
  const std::vector<std::pair<int, double>> levels = {{1, 1.0}, {4, 0.25}, {16, 0.125}};
  EXPECT_NEAR(worth_x_samples(levels, 4, 0.5), 2.0 / 4, 1e-12);            // first segment
  EXPECT_NEAR(worth_x_samples(levels, 4, 0.125 / std::sqrt(2.0)), 32.0 / 4, 1e-9);  // last, extended
}

TEST(ReportWorth, OneLevelIsTheUnbiasedRateAndBadInputIsUnknown) {
  EXPECT_NEAR(worth_x_samples({{16, 0.08}}, 16, 0.02), 4.0, 1e-12);
  EXPECT_EQ(worth_x_samples({}, 16, 0.02), -1);
  EXPECT_EQ(worth_x_samples({{16, 0.08}}, 16, 0.0), -1);
  EXPECT_EQ(worth_x_samples({{16, 0.08}}, 16, std::nan("")), -1);
  EXPECT_EQ(worth_x_samples({{1, 0.1}, {4, 0.2}}, 1, 0.05), -1);  // error grows with spp: no fit
}

TEST(ReportPareto, FrontMatchesTheDefinitionOnEveryPair) {
  // seconds, error: (1, 5) (2, 3) (2, 4) (3, 3) (4, 1) (4, 1) (5, 2)
  const std::vector<std::pair<double, double>> p = {{1, 5}, {2, 3}, {2, 4}, {3, 3}, {4, 1}, {4, 1}, {5, 2}};
  const std::vector<bool> lower = pareto_front(p, true);
  const std::vector<bool> expect_lower = {true, true, false, false, true, true, false};
  EXPECT_EQ(lower, expect_lower);
  // Higher is better (SSIM): (5, 2) is beaten by (1, 5) (faster and higher).
  const std::vector<bool> higher = pareto_front(p, false);
  const std::vector<bool> expect_higher = {true, false, false, false, false, false, false};
  EXPECT_EQ(higher, expect_higher);
}

TEST(ReportScaling, SlopeOfAKnownPowerLaw) {
  std::vector<ScalingRow> rows;
  for (int n : {256, 512, 1024, 2048}) rows.push_back({"f", "flat", n, n, 3e-7 * std::pow(double(n) * n, 1.25), 2.0 * n * n / 1e6});
  const ScalingFit fit = fit_scaling(rows);
  EXPECT_NEAR(fit.slope, 1.25, 1e-9);
  EXPECT_NEAR(fit.seconds_per_megapixel, 3e-7 * std::pow(2048.0 * 2048, 1.25) / (2048.0 * 2048 / 1e6), 1e-9);
  EXPECT_NEAR(fit.peak_memory_mb_per_megapixel, 2.0, 1e-12);
}

}  // namespace mcr
