// The factored (fast) sheared filter against the brute-force 4D filter it approximates
// (relMSE <= 0.01 on smooth random slope fields, on a step in slopes, with skewed axes), the
// closed form of a field of one slope, and thread counts.
#include "filters/lightfield/sheared.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "filters/lightfield/sheared4d.h"
#include "lightfield_testutil.h"
#include "metrics/metrics.h"

namespace mcr {
namespace {

using testutil::make_lightfield;

Image run_fast(const LightField& lf, const lf::Options& o, int nthreads = 0, lf::Counts* c = nullptr) {
  Image out(lf.width, lf.height, 3);
  sheared_lightfield(lf, o, Roi::all(lf.width, lf.height), nthreads, out, c);
  return out;
}

Image run4d(const LightField& lf, const lf::Options& o) {
  Image out(lf.width, lf.height, 3);
  sheared4d_lightfield(lf, o, Roi::all(lf.width, lf.height), 0, out, nullptr);
  return out;
}

// Visibility-like values: a sharp edge over (y1, y2) whose place moves over the image, plus a
// smooth part; positive, and noisy per pixel (its own mean is far from the filtered value).
void fill_mixed(LightField& lf) {
  testutil::fill_values(lf, [](double X1, double X2, double y1, double y2) {
    const double edge = y1 + 0.6 * y2 + 0.5 * std::sin(0.23 * X1) + 0.4 * std::cos(0.17 * X2);
    return (edge > 0 ? 1.0 : 0.15) + 0.2 * std::sin(2.0 * y2 + 0.3 * X1);
  });
}

// Smooth random bounds: smin in [lo, hi], smax = smin * (1.3 .. 2).
void smooth_random_slopes(LightField& lf, float lo, float hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 6.283f);
  const float a = u(rng), b = u(rng), c = u(rng);
  for (int y = 0; y < lf.height; ++y)
    for (int x = 0; x < lf.width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      const float t = 0.5f + 0.25f * std::sin(0.15f * float(x) + a) + 0.25f * std::sin(0.11f * float(y) + b);
      const float smin = lo + (hi - lo) * t;
      lf.smin[p] = smin;
      lf.smax[p] = smin * (1.65f + 0.35f * std::sin(0.13f * float(x + y) + c));
    }
}

// relMSE of the fast filter against the 4D one; the 4D one must itself be far from the
// pixels' own means (the case filters something).
double rel(const LightField& lf, const lf::Options& o) {
  const Image a = run4d(lf, o), b = run_fast(lf, o);
  const double own = relmse(a, testutil::plain_mean(lf), 1);
  EXPECT_GT(own, 0.01) << "the case filters nothing";
  std::printf("  (own means against sheared4d: relMSE %.4f)\n", own);
  const double e = relmse(a, b, 1);
  EXPECT_LT(e, own / 4);
  return e;
}

lf::Options opts(int max_width) {
  lf::Options o;
  o.max_width = max_width;
  return o;
}

TEST(Sheared, MatchesSheared4dOnSmoothRandomSlopesDof) {
  for (int l : {2, 3, 4}) {
    LightField lf = make_lightfield(LightFieldEffect::Dof, 40, 36, l, 1.0f, 0.5f, false);
    testutil::jitter_samples(lf, 10u + unsigned(l));
    smooth_random_slopes(lf, 1.0f, 6.0f, 3u + unsigned(l));
    fill_mixed(lf);
    const double e = rel(lf, opts(16));
    std::printf("dof smooth l=%d relMSE %.5f\n", l, e);
    EXPECT_LE(e, 0.01) << "l = " << l;
  }
}

TEST(Sheared, MatchesSheared4dOnSmoothRandomSlopesNegative) {
  LightField lf = make_lightfield(LightFieldEffect::Dof, 40, 36, 3, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 21);
  smooth_random_slopes(lf, 1.0f, 6.0f, 22);
  for (std::size_t p = 0; p < lf.pixels(); ++p) {  // behind the focus plane: both bounds negative
    const float a = lf.smin[p], b = lf.smax[p];
    lf.smin[p] = -b;
    lf.smax[p] = -a;
  }
  fill_mixed(lf);
  const double e = rel(lf, opts(16));
  std::printf("dof negative relMSE %.5f\n", e);
  EXPECT_LE(e, 0.01);
}

TEST(Sheared, MatchesSheared4dOnAStepInSlopes) {
  LightField lf = make_lightfield(LightFieldEffect::Dof, 40, 36, 3, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 31);
  for (int y = 0; y < lf.height; ++y)
    for (int x = 0; x < lf.width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      lf.smin[p] = x < 20 ? 1.0f : 4.0f;
      lf.smax[p] = x < 20 ? 1.6f : 7.0f;
    }
  fill_mixed(lf);
  const double e = rel(lf, opts(16));
  std::printf("dof step relMSE %.5f\n", e);
  EXPECT_LE(e, 0.01);
}

TEST(Sheared, MatchesSheared4dWithSkewedAxes) {
  for (int l : {2, 4}) {
    LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 40, 36, l, 1.0f, 0.5f, false);
    testutil::jitter_samples(lf, 41u + unsigned(l));
    testutil::set_axes(lf, 1.3f, 0.5f, -0.4f, 1.1f);
    smooth_random_slopes(lf, 1.0f, 6.0f, 42u + unsigned(l));
    fill_mixed(lf);
    const double e = rel(lf, opts(16));
    std::printf("skewed l=%d relMSE %.5f\n", l, e);
    EXPECT_LE(e, 0.01) << "l = " << l;
  }
}

TEST(Sheared, MatchesSheared4dOnAStepWithSkewedAxes) {
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 40, 36, 3, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 51);
  testutil::set_axes(lf, 0.8f, -0.6f, 0.7f, 0.9f);
  for (int y = 0; y < lf.height; ++y)
    for (int x = 0; x < lf.width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      lf.smin[p] = x + y < 38 ? 0.8f : 3.0f;
      lf.smax[p] = x + y < 38 ? 1.5f : 6.0f;
    }
  fill_mixed(lf);
  const double e = rel(lf, opts(16));
  std::printf("skewed step relMSE %.5f\n", e);
  EXPECT_LE(e, 0.01);
}

// The closed form of sheared4d_test's field of one slope, through the factored steps. Here
// sigma_y = L / 5 (the closed form needs the y range to cover the sheared Gaussian), so 16 bins
// over [-1.4, 1.4] lie 0.875 sigma_y apart (the paper's L = 2 sigma_y: 0.5 sigma_y) and their
// linear reading costs accuracy: 16 bins land well below the pixels' own means, 64 bins near the
// 4D filter's error (0.001), 4 bins lose the signal.
TEST(Sheared, OneSlopeFieldMatchesItsClosedForm) {
  const double A = 0.5, B = 0.3, C = 0.2, k1 = 7, k2 = 5;
  const float s = 40;
  LightField lf = make_lightfield(LightFieldEffect::Dof, 40, 40, 6, 1.0f, 0.2f, false);
  testutil::jitter_samples(lf, 61);
  testutil::set_slopes(lf, s, s);
  testutil::fill_values(lf, [&](double X1, double X2, double y1, double y2) {
    return A + B * std::sin(k1 * (y1 + X1 / s)) + C * std::cos(k2 * (y2 + X2 / s));
  });
  Image exact(40, 40, 3);
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double X1, X2;
    testutil::x_units(lf, p, &X1, &X2);
    const double v = A + B * std::exp(-k1 * k1 * 0.02) * std::sin(k1 * X1 / s) +
                     C * std::exp(-k2 * k2 * 0.02) * std::cos(k2 * X2 / s);  // sigma_y^2 / 2 = 0.02
    for (int c = 0; c < 3; ++c) exact.data()[p * 3 + std::size_t(c)] = float(v * (1.0 - 0.2 * c));
  }
  const double own = testutil::rms_diff(exact, testutil::plain_mean(lf));
  const double err = testutil::rms_diff(exact, run_fast(lf, opts(16)));  // 16 bins
  auto with_bins = [&](int bins) {
    lf::Options o = opts(16);
    o.bins = bins;
    return testutil::rms_diff(exact, run_fast(lf, o));
  };
  const double err4 = with_bins(4), err64 = with_bins(64);
  std::printf("closed form: own means %.5f, sheared 16 bins %.5f, 4 bins %.5f, 64 bins %.5f\n", own, err, err4, err64);
  EXPECT_LT(err, own / 5);
  EXPECT_LT(err64, 0.004);
  EXPECT_GT(err4, 2 * err);
  EXPECT_GT(err, 2 * err64);
}

TEST(Sheared, MatchesSheared4dNextToPixelsWithNothingToShear) {
  // Depth of field: the left half in focus (bounds 0: own samples), the right half blurred, a
  // band of opposite-sign bounds (the axis-aligned fallback) between them.
  LightField lf = make_lightfield(LightFieldEffect::Dof, 40, 36, 3, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 81);
  for (int y = 0; y < lf.height; ++y)
    for (int x = 0; x < lf.width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      lf.smin[p] = x < 16 ? 0.0f : x < 20 ? -1.0f : 2.0f;
      lf.smax[p] = x < 16 ? 0.0f : x < 20 ? 3.0f : 3.5f;
    }
  fill_mixed(lf);
  const double e = rel(lf, opts(16));
  std::printf("in focus | fallback | blurred: relMSE %.5f\n", e);
  EXPECT_LE(e, 0.01);
}

TEST(Sheared, MatchesSheared4dWithRejectionAtAnEdge) {
  // Soft shadows on two planes meeting at x = 20: a 60 degree fold and a depth step; rejection
  // in both filters (the fast one between P and each Q_j of its two lines, so the sets differ).
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 40, 36, 3, 1.0f, 0.5f, true);
  testutil::jitter_samples(lf, 91);
  testutil::set_axes(lf, 2, 0, 0, 2);
  smooth_random_slopes(lf, 1.0f, 6.0f, 92);
  for (int y = 0; y < lf.height; ++y)
    for (int x = 0; x < lf.width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(lf.width) + std::size_t(x);
      lf.px[p] = (float(x) + 0.5f) / 2;
      lf.py[p] = (float(y) + 0.5f) / 2;
      lf.pz[p] = x < 20 ? 0.0f : 3.0f;
      if (y > 18) lf.nx[p] = std::sin(1.047f), lf.nz[p] = std::cos(1.047f);
    }
  fill_mixed(lf);
  const double e = rel(lf, opts(16));
  std::printf("rejection at an edge: relMSE %.5f\n", e);
  EXPECT_LE(e, 0.01);
}

TEST(Sheared, SameBitsOnAnyThreadCountWithManyY2Values) {
  // Independent random y per sample (no shared jitter): l*l distinct y2 values per pixel.
  LightField lf = make_lightfield(LightFieldEffect::Dof, 33, 21, 3, 1.0f, 0.5f, false);
  std::mt19937 rng(71);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (std::size_t k = 0; k < lf.samples(); ++k) {
    lf.y1[k] = u(rng);
    lf.y2[k] = u(rng);
  }
  smooth_random_slopes(lf, 1.0f, 6.0f, 72);
  fill_mixed(lf);
  EXPECT_TRUE(testutil::same_bits(run_fast(lf, opts(16), 1), run_fast(lf, opts(16), 2)));
  EXPECT_LE(rel(lf, opts(16)), 0.01);
}

TEST(Sheared, BandsOfRowsGiveTheSameBits) {
  // One-row bands (band_bytes 1) against one band, skewed axes (lines cross rows), a roi.
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 37, 31, 3, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 101);
  testutil::set_axes(lf, 0.9f, 0.7f, -0.5f, 1.2f);
  smooth_random_slopes(lf, 1.0f, 6.0f, 102);
  fill_mixed(lf);
  for (const Roi& roi : {Roi::all(37, 31), Roi{3, 5, 30, 22}}) {
    Image one(37, 31, 3, -1.0f), rows(37, 31, 3, -1.0f);
    lf::Options o = opts(16);
    sheared_lightfield(lf, o, roi, 0, one, nullptr);
    o.band_bytes = 1;
    sheared_lightfield(lf, o, roi, 0, rows, nullptr);
    EXPECT_TRUE(testutil::same_bits(one, rows));
  }
}

}  // namespace
}  // namespace mcr
