// Point-wise adaptive filter (Guo & Pan 2012): each rule on its own (variance estimate,
// radius mapping, outlier replacement), the filter against a brute-force weighted mean,
// feature edges, notes about dropped weights, and numerical stress.
#include "filters/image/pwaf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "util/error.h"
#include "kernels/noise_variance.h"
#include "prepare/outliers.h"

namespace mcr {
namespace {

using testutil::kInf;
using testutil::kNaN;
using testutil::named_pass;

Frame frame_of(const Image& colour) {
  Frame f;
  f.width = colour.width();
  f.height = colour.height();
  f.path = "test.exr";
  f.passes.push_back(named_pass(Role::Colour, "Combined", colour));
  return f;
}

Image random_image(int w, int h, unsigned seed, float lo = 0.0f, float hi = 1.0f, int channels = 3) {
  return testutil::random_image(w, h, channels, seed, lo, hi);
}

// A frame with every feature pass, smooth geometry (two planes meeting at x = w/2).
Frame full_frame(int w, int h, unsigned seed, bool second = true, bool variance = true) {
  Frame f = frame_of(random_image(w, h, seed, 0.2f, 0.8f));
  Image n(w, h, 3), p(w, h, 3), v(w, h, 1, 0.01f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool left = x < w / 2;
      n.at(x, y, 0) = left ? 0.0f : 1.0f;
      n.at(x, y, 2) = left ? 1.0f : 0.0f;
      p.at(x, y, 0) = 0.01f * x;
      p.at(x, y, 1) = 0.01f * y;
      p.at(x, y, 2) = left ? 1.0f : 1.0f + 0.01f * (x - w / 2);
    }
  f.passes.push_back(named_pass(Role::Normal, "Normal", n));
  f.passes.push_back(named_pass(Role::Position, "Position", p));
  if (second) {
    f.passes.push_back(named_pass(Role::SecondNormal, "second_normal", n));
    f.passes.push_back(named_pass(Role::SecondPosition, "second_position", p));
  }
  if (variance) f.passes.push_back(named_pass(Role::Variance, "variance", v));
  return f;
}

// The shared run, plus the filter's statistics of that run.
struct PwafRun : testutil::Result {
  PwafStats stats;
};

PwafRun run_pwaf(const Frame& frame, const std::vector<std::pair<std::string, ParamValue>>& params = {}, int nthreads = 0,
             Roi roi = {}) {
  PwafFilter f;
  PwafRun r;
  static_cast<testutil::Result&>(r) = testutil::run_filter(f, frame, params, nthreads, roi);
  r.stats = f.stats();
  return r;
}

bool all_finite(const Image& im) {
  for (float v : im.storage())
    if (!std::isfinite(v)) return false;
  return true;
}

bool any_note_mentions(const std::vector<std::string>& notes, const std::string& word) {
  for (const auto& n : notes)
    if (n.find(word) != std::string::npos) return true;
  return false;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// ---------------------------------------------------------------------------------------------
// Registry and parameters

TEST(PwafFilterTest, RegisteredWithItsTable) {
  auto f = make_filter("pwaf");
  EXPECT_EQ(f->info().name, "pwaf");
  EXPECT_FALSE(f->info().nonfinite_policy.empty());
  for (const char* p : {"min_radius", "max_radius", "adaptive", "variance_max", "sigma_p", "sigma_c", "sigma_n",
                        "sigma_sp", "sigma_sn", "outlier_k", "demodulate"})
    EXPECT_TRUE(f->params().has(p)) << p;
}

TEST(PwafFilterTest, MinRadiusAboveMaxRadiusIsRejectedAtCommit) {
  PwafFilter f;
  f.set("min_radius", std::int64_t(5));
  f.set("max_radius", std::int64_t(3));
  try {
    f.commit();
    FAIL() << "commit accepted min_radius > max_radius";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("min_radius"), std::string::npos);
  }
}

// ---------------------------------------------------------------------------------------------
// Variance estimator

std::vector<double> interior(const std::vector<double>& v, int w, int h, int margin) {
  std::vector<double> r;
  for (int y = margin; y < h - margin; ++y)
    for (int x = margin; x < w - margin; ++x) r.push_back(v[std::size_t(y) * w + x]);
  return r;
}

TEST(PwafVarianceTest, RecoversKnownVarianceOfNoiseOnFlatAndLinearSignals) {
  const int w = 96, h = 96;
  const double sigma = 0.1;
  for (bool ramp : {false, true}) {
    std::mt19937 rng(3);
    std::normal_distribution<double> g(0.0, sigma);
    Image im(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c)
          im.at(x, y, c) = float((ramp ? 0.2 + 0.01 * x + 0.005 * y : 0.5) + g(rng));
    const std::vector<std::uint8_t> valid(std::size_t(w) * h, 1);
    const std::vector<double> v = estimate_variance(im, valid, nullptr, 3, Roi::all(w, h), 2);
    const std::vector<double> in = interior(v, w, h, 4);
    double mean = 0;
    for (double x : in) mean += x;
    mean /= double(in.size());
    // Stated tolerance: the mean over the image within 5%, the median within 8%, and 90% of
    // pixels within 40% of sigma^2 (49 correlated residuals per pixel).
    EXPECT_NEAR(mean, sigma * sigma, 0.05 * sigma * sigma) << (ramp ? "ramp" : "flat");
    EXPECT_NEAR(median(in), sigma * sigma, 0.08 * sigma * sigma) << (ramp ? "ramp" : "flat");
    std::size_t close = 0;
    for (double x : in) close += std::fabs(x / (sigma * sigma) - 1.0) < 0.4;
    EXPECT_GT(double(close) / double(in.size()), 0.9) << (ramp ? "ramp" : "flat");
  }
}

TEST(PwafVarianceTest, SampleCountDividesThePerSampleVariance) {
  // Per-sample standard deviation 0.4; 4 samples on the left half, 16 on the right: pixel
  // variances 0.04 and 0.01, recovered on each side, next to the boundary too.
  const int w = 96, h = 64;
  const double s = 0.4;
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  Image im(w, h, 3), n(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float spp = x < w / 2 ? 4.0f : 16.0f;
      n.at(x, y, 0) = spp;
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = float(0.5 + g(rng) * s / std::sqrt(spp));
    }
  const std::vector<std::uint8_t> valid(std::size_t(w) * h, 1);
  const std::vector<double> v = estimate_variance(im, valid, &n, 3, Roi::all(w, h), 1);
  std::vector<double> left, right, left_edge, right_edge;
  for (int y = 4; y < h - 4; ++y) {
    for (int x = 4; x < w / 2 - 4; ++x) left.push_back(v[std::size_t(y) * w + x]);
    for (int x = w / 2 + 4; x < w - 4; ++x) right.push_back(v[std::size_t(y) * w + x]);
    left_edge.push_back(v[std::size_t(y) * w + w / 2 - 1]);
    right_edge.push_back(v[std::size_t(y) * w + w / 2]);
  }
  EXPECT_NEAR(median(left), 0.04, 0.1 * 0.04);
  EXPECT_NEAR(median(right), 0.01, 0.1 * 0.01);
  EXPECT_NEAR(median(left_edge), 0.04, 0.15 * 0.04);
  EXPECT_NEAR(median(right_edge), 0.01, 0.15 * 0.01);
  // Without the sample counts both sides get one (mixed) level near the boundary: the pass matters.
  const std::vector<double> plain = estimate_variance(im, valid, nullptr, 3, Roi::all(w, h), 1);
  EXPECT_GT(plain[std::size_t(h / 2) * w + w / 2] / v[std::size_t(h / 2) * w + w / 2], 1.5);
}

TEST(PwafVarianceTest, VariancePassIsUsedWhenPresent) {
  // A clean step between two flat colours: a tiny variance pass keeps the colour kernel
  // tight (edge kept), a large one widens it (edge smoothed). No estimate is involved.
  Image im(32, 8, 3, 0.0f);
  for (int y = 0; y < 8; ++y)
    for (int x = 16; x < 32; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 0.1f;
  Frame f = frame_of(im);
  f.passes.push_back(named_pass(Role::Variance, "variance", Image(32, 8, 1, 1e-8f)));
  // firefly_k=0: no outlier step, whose count would be one more note; exposure=off: this frame
  // (mean luminance 0.05) would be filtered at 4x, one more note.
  const PwafRun tight =
      run_pwaf(f, {{"adaptive", false}, {"demodulate", false}, {"firefly_k", 0.0}, {"exposure", std::string("off")}});
  EXPECT_TRUE(tight.stats.variance_from_pass);
  EXPECT_TRUE(tight.notes.size() == 3u) << "only the dropped weights are noted";
  EXPECT_NEAR(tight.out.at(15, 4, 0), 0.0f, 1e-4);
  f.passes.back().image = Image(32, 8, 1, 0.5f);
  const PwafRun wide = run_pwaf(f, {{"adaptive", false}, {"demodulate", false}});
  EXPECT_GT(wide.out.at(15, 4, 0), 0.01f);
}

TEST(PwafVarianceTest, VariancePassFollowsDemodulation) {
  // Demodulating by a constant albedo 0.5 must be the same as filtering colour / 0.5 with the
  // variance / 0.25, then multiplying by 0.5: the pass is divided by albedo^2 too.
  Frame a = full_frame(20, 14, 36, true, true);
  a.passes.push_back(named_pass(Role::Albedo, "albedo", Image(20, 14, 3, 0.5f)));
  Frame b = full_frame(20, 14, 36, true, true);
  for (Pass& p : b.passes) {
    if (p.role == Role::Colour)
      for (float& v : p.image.storage()) v *= 2.0f;
    if (p.role == Role::Variance)
      for (float& v : p.image.storage()) v *= 4.0f;
  }
  const PwafRun ra = run_pwaf(a, {{"demodulate", true}}), rb = run_pwaf(b);
  for (std::size_t k = 0; k < ra.out.storage().size(); ++k)
    ASSERT_EQ(ra.out.storage()[k], 0.5f * rb.out.storage()[k]) << k;
}

// ---------------------------------------------------------------------------------------------
// Radius mapping

TEST(PwafRadiusTest, LinearInRelativeVarianceAndClamped) {
  // rho_max = 1: six equal steps from min 2 to max 8.
  for (int k = 0; k <= 6; ++k) EXPECT_EQ(pwaf::window_radius(k / 6.0, 1.0, 2, 8), 2 + k) << k;
  // Linear: the midpoint maps to the middle radius, for any rho_max.
  EXPECT_EQ(pwaf::window_radius(0.5e-6, 1e-6, 0, 10), 5);
  EXPECT_EQ(pwaf::window_radius(50.0, 100.0, 4, 16), 10);
  // Clamped at both ends.
  EXPECT_EQ(pwaf::window_radius(0.0, 1.0, 2, 8), 2);
  EXPECT_EQ(pwaf::window_radius(7.0, 1.0, 2, 8), 8);
  EXPECT_EQ(pwaf::window_radius(1e300, 1.0, 2, 8), 8);
  // Unknown noise is treated as the worst case; a noise-free frame (rho_max 0) keeps min.
  EXPECT_EQ(pwaf::window_radius(std::nan(""), 1.0, 2, 8), 8);
  EXPECT_EQ(pwaf::window_radius(-1.0, 1.0, 2, 8), 8);
  EXPECT_EQ(pwaf::window_radius(0.0, 0.0, 2, 8), 2);
  EXPECT_EQ(pwaf::window_radius(1e-9, 0.0, 2, 8), 8);
  // relative_variance is v / (Y^2 + 0.01).
  EXPECT_DOUBLE_EQ(pwaf::relative_variance(0.02, 0.1), 0.02 / 0.02);
}

TEST(PwafRadiusTest, NoisyRegionGetsLargerWindowsThanQuietOne) {
  // A noisy quarter on the left, the rest nearly clean: the noisy part, far above the frame's
  // median relative variance, gets max_radius; the quiet part, around the median, much less.
  const int w = 64, h = 32;
  Image im(w, h, 3);
  std::mt19937 rng(9);
  std::normal_distribution<float> g(0.0f, 1.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 0.5f + (x < w / 4 ? 0.2f : 0.002f) * g(rng);
  const Frame f = frame_of(im);
  const PwafRun noisy = run_pwaf(f, {}, 0, Roi{0, 0, w / 4 - 4, h});
  const PwafRun quiet = run_pwaf(f, {}, 0, Roi{w / 4 + 4, 0, w, h});
  EXPECT_EQ(noisy.stats.mean_radius, 8.0);
  EXPECT_LT(quiet.stats.mean_radius, 6.5);
  EXPECT_GE(quiet.stats.mean_radius, 2.0);
  EXPECT_GT(noisy.stats.median_rel_variance, 0.0);
  const PwafRun fixed = run_pwaf(f, {{"adaptive", false}}, 0, Roi{w / 4 + 4, 0, w, h});
  EXPECT_EQ(fixed.stats.mean_radius, 8.0);
}

// ---------------------------------------------------------------------------------------------
// Outlier replacement

TEST(PwafOutlierTest, PlantedFireflyIsReplacedByNeighbourhoodMeanAndNothingElseChanges) {
  const int w = 24, h = 20;
  // Bounded noise (+-10% of 0.5): no ordinary pixel is 5 standard deviations above its neighbours.
  Image im = random_image(w, h, 11, 0.45f, 0.55f);
  const int fx = 9, fy = 7;
  for (int c = 0; c < 3; ++c) im.at(fx, fy, c) = 1e4f;
  const OutlierResult r = replace_outliers(im, 3, 5.0, Roi::all(w, h), 2);
  double want[3] = {0, 0, 0};
  int n = 0;
  for (int y = fy - 3; y <= fy + 3; ++y)
    for (int x = fx - 3; x <= fx + 3; ++x) {
      if (x == fx && y == fy) continue;
      for (int c = 0; c < 3; ++c) want[c] += im.at(x, y, c);
      ++n;
    }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.colour.at(fx, fy, c), want[c] / n, 1e-6);
  EXPECT_EQ(r.replaced[std::size_t(fy) * w + fx], 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (x == fx && y == fy) continue;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(r.colour.at(x, y, c), im.at(x, y, c)) << x << "," << y;
      ASSERT_EQ(r.replaced[std::size_t(y) * w + x], 0);
    }
}

TEST(PwafOutlierTest, DisabledByKZeroButNonFiniteStillRepaired) {
  Image im = random_image(12, 12, 12, 0.45f, 0.55f);
  for (int c = 0; c < 3; ++c) im.at(3, 3, c) = 1e4f;
  im.at(8, 8, 1) = kNaN;
  const OutlierResult r = replace_outliers(im, 2, 0.0, Roi::all(12, 12), 1);
  EXPECT_EQ(r.colour.at(3, 3, 0), 1e4f);
  EXPECT_EQ(r.replaced[8 * 12 + 8], 2);
  EXPECT_TRUE(std::isfinite(r.colour.at(8, 8, 1)));
  EXPECT_EQ(r.valid[8 * 12 + 8], 1);
}

TEST(PwafOutlierTest, FilterOutputNearAFireflyStaysAtTheBackground) {
  // Both 3.3 mechanisms suppress a firefly: the outlier replacement, and the estimated range
  // value (the centre is compared through a Gaussian of its neighbourhood, not its own spike).
  // With both off, the spike survives.
  Image im = random_image(40, 40, 13, 0.4f, 0.6f);
  for (int c = 0; c < 3; ++c) im.at(20, 20, c) = 1e5f;
  const Frame f = frame_of(im);
  auto worst = [&](const PwafRun& r) {
    float m = 0;
    for (int y = 14; y <= 26; ++y)
      for (int x = 14; x <= 26; ++x) m = std::max(m, r.out.at(x, y, 0));
    return m;
  };
  // firefly_k=0 throughout: pwaf's own mechanisms, without the common outlier step.
  const PwafRun both = run_pwaf(f, {{"firefly_k", 0.0}});
  EXPECT_LE(worst(both), 0.6f);
  EXPECT_EQ(both.stats.outliers_replaced, 1u);
  const PwafRun replacement_only = run_pwaf(f, {{"prefilter_sigma", 0.0}, {"firefly_k", 0.0}});
  EXPECT_LE(worst(replacement_only), 0.6f);
  const PwafRun range_only = run_pwaf(f, {{"outlier_k", 0.0}, {"firefly_k", 0.0}});
  EXPECT_LT(worst(range_only), 1.0f);
  const PwafRun neither = run_pwaf(f, {{"outlier_k", 0.0}, {"prefilter_sigma", 0.0}, {"firefly_k", 0.0}});
  EXPECT_GT(worst(neither), 1.0f);
}

// ---------------------------------------------------------------------------------------------
// The filter against a brute-force weighted mean

TEST(PwafFilterTest, FeatureWeightsOffAndFixedWindowIsAGaussianWeightedMean) {
  const int w = 21, h = 17, r = 3;
  const double sp = 1.7;
  const Frame f = full_frame(w, h, 21);
  const Image& in = f.image(Role::Colour);
  const PwafRun run = run_pwaf(f, {{"adaptive", false},
                               {"min_radius", std::int64_t(0)},
                               {"max_radius", std::int64_t(r)},
                               {"sigma_p", sp},
                               {"sigma_c", 1e6},
                               {"sigma_n", 1e6},
                               {"sigma_sp", 1e6},
                               {"sigma_sn", 1e6},
                               {"outlier_k", 0.0}});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s[3] = {0, 0, 0}, sw = 0;
      for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
        for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx) {
          const double g = std::exp(-0.5 * ((xx - x) * (xx - x) + (yy - y) * (yy - y)) / (sp * sp));
          for (int c = 0; c < 3; ++c) s[c] += g * in.at(xx, yy, c);
          sw += g;
        }
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(run.out.at(x, y, c), s[c] / sw, 1e-6) << x << "," << y << " c" << c;
    }
}

// The vectorised window (kernels/pwaf_window.h) against eq. 8 written out in double: Gp, Gn
// and Gsn on random normals (one NaN: that pixel's Gn is off in every pair it is part of),
// colour weight off, fixed windows, on a frame whose width is not a multiple of any lane count.
TEST(PwafFilterTest, FeatureWeightsMatchEquation8WrittenOut) {
  const int w = 23, h = 13, r = 4;
  const double sp = 2.1, sn = 0.6, ssn = 0.9;
  Frame f = frame_of(random_image(w, h, 61, 0.1f, 0.9f));
  Image n1 = random_image(w, h, 62, -1.0f, 1.0f), n2 = random_image(w, h, 63, -1.0f, 1.0f);
  n1.at(9, 6, 1) = kNaN;
  f.passes.push_back(named_pass(Role::Normal, "Normal", n1));
  f.passes.push_back(named_pass(Role::SecondNormal, "second_normal", n2));
  const PwafRun run = run_pwaf(f, {{"adaptive", false},
                                   {"max_radius", std::int64_t(r)},
                                   {"sigma_p", sp},
                                   {"sigma_c", 1e6},
                                   {"sigma_n", sn},
                                   {"sigma_sn", ssn},
                                   {"outlier_k", 0.0}});
  const Image& in = f.image(Role::Colour);
  auto d2 = [](const Image& im, int x0, int y0, int x1, int y1) {
    double s = 0;
    for (int c = 0; c < 3; ++c) s += std::pow(double(im.at(x0, y0, c)) - double(im.at(x1, y1, c)), 2);
    return s;
  };
  auto finite = [&](int x, int y) { return std::isfinite(n1.at(x, y, 0) + n1.at(x, y, 1) + n1.at(x, y, 2)); };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s[3] = {0, 0, 0}, sw = 0;
      for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
        for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx) {
          double e = 0.5 * ((xx - x) * (xx - x) + (yy - y) * (yy - y)) / (sp * sp);
          if (finite(x, y) && finite(xx, yy)) e += d2(n1, x, y, xx, yy) / (2 * sn * sn);
          e += d2(n2, x, y, xx, yy) / (2 * ssn * ssn);
          const double g = std::exp(-e);
          for (int c = 0; c < 3; ++c) s[c] += g * in.at(xx, yy, c);
          sw += g;
        }
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(run.out.at(x, y, c), s[c] / sw, 2e-6) << x << "," << y << " c" << c;
    }
}

TEST(PwafFilterTest, NormalEdgeIsPreserved) {
  // Two flat colours meeting where the normal turns by 90 degrees; the colour kernel is off,
  // so only Gn can keep them apart.
  const int w = 32, h = 16;
  Image im(w, h, 3), n(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool left = x < w / 2;
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = left ? 0.2f : 0.8f;
      n.at(x, y, left ? 2 : 0) = 1.0f;
    }
  Frame f = frame_of(im);
  f.passes.push_back(named_pass(Role::Normal, "Normal", n));
  const std::vector<std::pair<std::string, ParamValue>> common = {{"adaptive", false}, {"sigma_c", 1e6}};
  auto with_sigma_n = [&](double s) {
    auto p = common;
    p.emplace_back("sigma_n", s);
    return run_pwaf(f, p).out;
  };
  const Image kept = with_sigma_n(0.1), blurred = with_sigma_n(1e6);
  for (int y = 0; y < h; ++y) {
    EXPECT_NEAR(kept.at(w / 2 - 1, y, 0), 0.2f, 1e-4);
    EXPECT_NEAR(kept.at(w / 2, y, 0), 0.8f, 1e-4);
    EXPECT_GT(blurred.at(w / 2 - 1, y, 0), 0.25f);  // without Gn the edge does blur
  }
}

TEST(PwafFilterTest, SecondHitPositionEdgeIsPreserved) {
  // A mirror-like case: same colour scale, same first-hit normal, but the second hits jump.
  const int w = 32, h = 8;
  Image im(w, h, 3), sp(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool left = x < w / 2;
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = left ? 0.3f : 0.6f;
      sp.at(x, y, 0) = 0.01f * x;
      sp.at(x, y, 2) = left ? 1.0f : 5.0f;
    }
  Frame f = frame_of(im);
  f.passes.push_back(named_pass(Role::SecondPosition, "second_position", sp));
  const PwafRun kept = run_pwaf(f, {{"adaptive", false}, {"sigma_c", 1e6}});
  const PwafRun blurred = run_pwaf(f, {{"adaptive", false}, {"sigma_c", 1e6}, {"sigma_sp", 1e6}});
  EXPECT_NEAR(kept.out.at(w / 2 - 1, 4, 0), 0.3f, 1e-4);
  EXPECT_GT(blurred.out.at(w / 2 - 1, 4, 0), 0.35f);
}

// ---------------------------------------------------------------------------------------------
// Notes and fallbacks for missing second-hit passes

TEST(PwafNotesTest, NamesTheDroppedWeightsWhenSecondHitPassesAreAbsent) {
  const PwafRun r = run_pwaf(full_frame(16, 12, 31, /*second=*/false));
  EXPECT_TRUE(any_note_mentions(r.notes, "no second_position pass; Gsp uses the first-hit position")) << r.notes.size();
  EXPECT_TRUE(any_note_mentions(r.notes, "no second_normal pass; Gsn dropped"));
  EXPECT_FALSE(any_note_mentions(r.notes, "Gn dropped"));

  // No position either: Gsp is dropped outright.
  Frame bare = frame_of(random_image(16, 12, 32));
  const PwafRun b = run_pwaf(bare);
  EXPECT_TRUE(any_note_mentions(b.notes, "Gsp dropped"));
  EXPECT_TRUE(any_note_mentions(b.notes, "Gsn dropped"));
  EXPECT_TRUE(any_note_mentions(b.notes, "Gn dropped"));
}

TEST(PwafNotesTest, NoNoteWhenEveryPassIsPresent) {
  Frame every = full_frame(16, 12, 33, /*second=*/true, /*variance=*/true);
  every.passes.push_back(named_pass(Role::Albedo, "albedo", random_image(16, 12, 34, 0.1f, 1.0f)));
  // firefly_k=0: no outlier step, whose count is a note of its own (not about a pass).
  const PwafRun r = run_pwaf(every, {{"firefly_k", 0.0}});
  EXPECT_TRUE(r.notes.empty()) << r.notes.front();
  // Without the variance pass only the estimate is noted, no weight is named.
  const PwafRun e = run_pwaf(full_frame(16, 12, 33, true, false));
  EXPECT_FALSE(any_note_mentions(e.notes, "Gsp"));
  EXPECT_FALSE(any_note_mentions(e.notes, "Gsn"));
  EXPECT_TRUE(any_note_mentions(e.notes, "variance estimated"));
}

TEST(PwafNotesTest, FirstHitPositionStandsInForTheSecondHitPosition) {
  // The documented fallback: no second_position -> Gsp on the position pass, exactly as if
  // that pass had been given as second_position.
  const Frame base = full_frame(20, 14, 34, false);
  Frame as_second = frame_of(base.image(Role::Colour));
  as_second.passes.push_back(named_pass(Role::Normal, "Normal", base.image(Role::Normal)));
  as_second.passes.push_back(named_pass(Role::SecondPosition, "second_position", base.image(Role::Position)));
  as_second.passes.push_back(named_pass(Role::Variance, "variance", base.image(Role::Variance)));
  const PwafRun a = run_pwaf(base), b = run_pwaf(as_second);
  EXPECT_EQ(a.out.storage(), b.out.storage());
}

TEST(PwafNotesTest, MissingSecondNormalDropsGsnRatherThanReusingTheFirstHitNormal) {
  // Gsn is dropped, not fed the first-hit normal (that would only sharpen Gn): the output
  // equals one with a constant second normal (Gsn = 1 everywhere).
  const Frame base = full_frame(20, 14, 35, false);
  Frame constant = base;
  constant.passes.push_back(named_pass(Role::SecondNormal, "second_normal", Image(20, 14, 3, 0.5f)));
  constant.passes.push_back(named_pass(Role::SecondPosition, "second_position", base.image(Role::Position)));
  const PwafRun a = run_pwaf(base), b = run_pwaf(constant);
  EXPECT_EQ(a.out.storage(), b.out.storage());
  // ...and differs from feeding the first-hit normal as the second normal.
  Frame reuse = base;
  reuse.passes.push_back(named_pass(Role::SecondNormal, "second_normal", base.image(Role::Normal)));
  reuse.passes.push_back(named_pass(Role::SecondPosition, "second_position", base.image(Role::Position)));
  const PwafRun c = run_pwaf(reuse, {{"sigma_n", 2.0}, {"sigma_sn", 0.5}});
  const PwafRun d = run_pwaf(base, {{"sigma_n", 2.0}, {"sigma_sn", 0.5}});
  EXPECT_NE(c.out.storage(), d.out.storage());
}

// ---------------------------------------------------------------------------------------------
// Numerical stress

void expect_clean(const PwafRun& r, const std::string& what) {
  EXPECT_TRUE(all_finite(r.out)) << what;
  EXPECT_EQ(r.repaired, 0u) << what;
}

// Every output channel lies within the range of the finite input values (a convex combination).
void expect_within_input_range(const Image& in, const Image& out, const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
    for (int y = 0; y < in.height(); ++y)
      for (int x = 0; x < in.width(); ++x)
        if (std::isfinite(in.at(x, y, c))) {
          lo = std::min(lo, in.at(x, y, c));
          hi = std::max(hi, in.at(x, y, c));
        }
    for (int y = 0; y < out.height(); ++y)
      for (int x = 0; x < out.width(); ++x) {
        ASSERT_GE(out.at(x, y, c), lo) << what;
        ASSERT_LE(out.at(x, y, c), hi) << what;
      }
  }
}

TEST(PwafStressTest, ConstantImageStaysConstant) {
  for (float v : {0.0f, 0.375f, -2.5f, 1e-30f, 1e30f, 3.3e38f, -3.3e38f, std::numeric_limits<float>::max()}) {
    Frame f = full_frame(13, 9, 40, true, false);
    f.passes[0].image = Image(13, 9, 3, v);
    for (bool adaptive : {true, false}) {
      const PwafRun c = run_pwaf(f, {{"adaptive", adaptive}});
      for (float o : c.out.storage()) ASSERT_EQ(o, v) << "constant " << v;
      expect_clean(c, "constant");
    }
  }
}

TEST(PwafStressTest, AllEqualFeaturesActLikeNoFeatures) {
  const Image colour = random_image(18, 14, 41);
  Frame plain = frame_of(colour);
  Frame same = plain;
  same.passes.push_back(named_pass(Role::Normal, "Normal", Image(18, 14, 3, 0.3f)));
  same.passes.push_back(named_pass(Role::Position, "Position", Image(18, 14, 3, 2.0f)));
  same.passes.push_back(named_pass(Role::SecondNormal, "second_normal", Image(18, 14, 3, -1.0f)));
  same.passes.push_back(named_pass(Role::SecondPosition, "second_position", Image(18, 14, 3, 7.0f)));
  const PwafRun a = run_pwaf(plain), b = run_pwaf(same);
  EXPECT_EQ(a.out.storage(), b.out.storage());
  expect_clean(b, "equal features");
}

TEST(PwafStressTest, SigmasAtTheirRangeLimits) {
  const Frame f = full_frame(20, 16, 42, true, false);
  const Image& in = f.image(Role::Colour);
  for (const char* name : {"sigma_p", "sigma_c", "sigma_n", "sigma_sp", "sigma_sn", "prefilter_sigma", "variance_max", "outlier_k"}) {
    const ParamSpec* spec = nullptr;
    for (const ParamSpec& s : PwafFilter::static_info().params)
      if (s.name == name) spec = &s;
    ASSERT_NE(spec, nullptr) << name;
    for (double v : {spec->min, spec->max}) {
      const PwafRun r = run_pwaf(f, {{name, v}});
      expect_clean(r, std::string(name) + "=" + std::to_string(v));
      expect_within_input_range(in, r.out, name);
    }
  }
  // Radii at their limits too.
  const PwafRun big = run_pwaf(f, {{"min_radius", std::int64_t(32)}, {"max_radius", std::int64_t(32)}});
  expect_clean(big, "radius 32");
  const PwafRun zero = run_pwaf(f, {{"min_radius", std::int64_t(0)}, {"max_radius", std::int64_t(0)}, {"outlier_k", 0.0}});
  EXPECT_EQ(zero.out.storage(), in.storage());  // radius 0: the pixel itself
}

TEST(PwafStressTest, DegenerateSizes) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{1, 9}, std::pair{9, 1}, std::pair{2, 2}, std::pair{1, 40}, std::pair{40, 1}}) {
    Frame f = full_frame(w, h, 43, true, false);
    for (bool adaptive : {true, false}) {
      const PwafRun r = run_pwaf(f, {{"adaptive", adaptive}});
      ASSERT_EQ(r.out.width(), w);
      ASSERT_EQ(r.out.height(), h);
      expect_clean(r, std::to_string(w) + "x" + std::to_string(h));
      expect_within_input_range(f.image(Role::Colour), r.out, "size");
    }
    if (w * h == 1) EXPECT_EQ(run_pwaf(f).out.storage(), f.image(Role::Colour).storage());
  }
}

TEST(PwafStressTest, TinyAndHugeValues) {
  for (float scale : {1e-30f, 1e30f, 3e38f}) {
    Frame f = full_frame(24, 18, 44, true, false);
    Image& c = f.passes[0].image;
    for (float& v : c.storage()) v *= scale;
    for (bool adaptive : {true, false}) {
      const PwafRun r = run_pwaf(f, {{"adaptive", adaptive}});
      expect_clean(r, "scale " + std::to_string(scale));
      expect_within_input_range(c, r.out, "scale");
      // Not flattened to 0 or a constant: the result keeps the input's magnitude.
      EXPECT_GT(r.out.at(12, 9, 0), 0.1f * scale);
    }
  }
  // Features at 1e30 and 1e-30 too.
  Frame g = full_frame(24, 18, 45, true, false);
  for (Pass& p : g.passes)
    if (p.role == Role::Position || p.role == Role::SecondPosition)
      for (float& v : p.image.storage()) v = v * 1e30f + 1e30f;
  expect_clean(run_pwaf(g), "positions 1e30");
  for (Pass& p : g.passes)
    if (p.role == Role::Position || p.role == Role::SecondPosition)
      for (float& v : p.image.storage()) v = v * 1e-30f * 1e-30f;
  expect_clean(run_pwaf(g), "positions 1e-30");
}

TEST(PwafStressTest, NonFiniteColourIsRepairedFromItsNeighbours) {
  Frame f = full_frame(24, 18, 46, true, false);
  Image& c = f.passes[0].image;
  const Image clean = c;
  c.at(5, 5, 0) = kNaN;
  c.at(10, 7, 1) = kInf;
  c.at(15, 9, 2) = -kInf;
  for (int ch = 0; ch < 3; ++ch) c.at(0, 0, ch) = kNaN;  // a corner
  for (bool adaptive : {true, false}) {
    const PwafRun r = run_pwaf(f, {{"adaptive", adaptive}});
    expect_clean(r, "non-finite colour");
    expect_within_input_range(clean, r.out, "non-finite colour");
    EXPECT_EQ(r.stats.nonfinite_replaced, 4u);
  }
  // A whole region of NaN wider than the outlier window: left out; its centre outputs what its
  // window finds (finite) -- and an all-NaN image outputs 0.
  Image all_nan(9, 9, 3, kNaN);
  const PwafRun z = run_pwaf(frame_of(all_nan));
  expect_clean(z, "all NaN");
  for (float v : z.out.storage()) EXPECT_EQ(v, 0.0f);
}

TEST(PwafStressTest, NonFiniteFeaturesSwitchTheirWeightOff) {
  for (Role role : {Role::Normal, Role::Position, Role::SecondNormal, Role::SecondPosition, Role::Variance}) {
    for (float bad : {kNaN, kInf, -kInf}) {
      Frame f = full_frame(20, 16, 47, true, true);
      for (Pass& p : f.passes)
        if (p.role == role) {
          p.image.at(7, 7, 0) = bad;
          for (int x = 0; x < 20; ++x) p.image.at(x, 12, p.image.channels() - 1) = bad;  // a whole row
        }
      const PwafRun r = run_pwaf(f);
      expect_clean(r, std::string(role_name(role)));
      expect_within_input_range(f.image(Role::Colour), r.out, role_name(role));
    }
  }
  // An all-NaN variance pass falls back to the estimate, and says so.
  Frame f = full_frame(20, 16, 48, true, true);
  for (Pass& p : f.passes)
    if (p.role == Role::Variance) p.image = Image(20, 16, 1, kNaN);
  const PwafRun r = run_pwaf(f);
  expect_clean(r, "NaN variance pass");
  EXPECT_TRUE(any_note_mentions(r.notes, "variance estimated"));
  // A feature NaN at one pixel gives the same result as that pixel's feature being absent
  // from the comparison: with sigma_n tiny, a NaN normal does not isolate the pixel.
  Frame g = full_frame(20, 16, 49, false, true);
  for (Pass& p : g.passes)
    if (p.role == Role::Normal) p.image.at(4, 4, 0) = kNaN;
  const PwafRun s = run_pwaf(g, {{"sigma_n", 1e-4}, {"adaptive", false}});
  EXPECT_NE(s.out.at(4, 4, 0), g.image(Role::Colour).at(4, 4, 0));
}

TEST(PwafStressTest, ZeroAlbedoWithDemodulation) {
  Frame f = full_frame(16, 12, 50, true, false);
  f.passes.push_back(named_pass(Role::Albedo, "albedo", Image(16, 12, 3, 0.0f)));
  const PwafRun r = run_pwaf(f, {{"demodulate", true}});
  expect_clean(r, "zero albedo");
  Frame g = f;
  for (Pass& p : g.passes)
    if (p.role == Role::Albedo) p.image.at(3, 3, 1) = kNaN;
  expect_clean(run_pwaf(g, {{"demodulate", true}}), "NaN albedo");
}

TEST(PwafStressTest, SameResultForOneAndTwoThreads) {
  const Frame f = full_frame(37, 29, 51, false, false);
  for (bool adaptive : {true, false}) {
    const PwafRun a = run_pwaf(f, {{"adaptive", adaptive}}, 1), b = run_pwaf(f, {{"adaptive", adaptive}}, 2);
    EXPECT_EQ(a.out.storage(), b.out.storage());
  }
}

TEST(PwafStressTest, RoiChangesOnlyPixelsInsideAndMatchesTheWholeFrame) {
  Frame f = full_frame(40, 30, 52, false, false);
  for (int c = 0; c < 3; ++c) f.passes[0].image.at(20, 15, c) = 1e4f;  // a firefly inside
  const Image& in = f.image(Role::Colour);
  const Roi roi{7, 5, 26, 21};
  for (bool adaptive : {true, false}) {
    const PwafRun whole = run_pwaf(f, {{"adaptive", adaptive}});
    const PwafRun part = run_pwaf(f, {{"adaptive", adaptive}}, 2, roi);
    for (int y = 0; y < 30; ++y)
      for (int x = 0; x < 40; ++x)
        for (int c = 0; c < 3; ++c) {
          const bool inside = x >= roi.x0 && x < roi.x1 && y >= roi.y0 && y < roi.y1;
          if (inside) ASSERT_EQ(part.out.at(x, y, c), whole.out.at(x, y, c)) << x << "," << y;
          else ASSERT_EQ(part.out.at(x, y, c), in.at(x, y, c)) << x << "," << y;
        }
  }
}

// Demodulated by default (pwaf has no albedo weight): with an albedo pass the default is
// demodulate=true; without one the step is skipped with a note, and only a demodulate=true
// the user gave is an error.
TEST(PwafNotesTest, DemodulatesByDefaultWhenThereIsAnAlbedo) {
  EXPECT_TRUE(PwafFilter().params().get_bool("demodulate"));
  Frame with_albedo = full_frame(20, 14, 37, true, false);
  with_albedo.passes.push_back(named_pass(Role::Albedo, "albedo", random_image(20, 14, 38, 0.1f, 1.0f)));
  EXPECT_EQ(run_pwaf(with_albedo).out.storage(), run_pwaf(with_albedo, {{"demodulate", true}}).out.storage());
  EXPECT_NE(run_pwaf(with_albedo).out.storage(), run_pwaf(with_albedo, {{"demodulate", false}}).out.storage());
  const Frame without = full_frame(20, 14, 37, true, false);
  PwafRun skipped;
  ASSERT_NO_THROW(skipped = run_pwaf(without));
  EXPECT_TRUE(any_note_mentions(skipped.notes, "demodulation skipped"));
  EXPECT_EQ(skipped.out.storage(), run_pwaf(without, {{"demodulate", false}}).out.storage());
  EXPECT_THROW(run_pwaf(without, {{"demodulate", true}}), Error);
}

}  // namespace
}  // namespace mcr
