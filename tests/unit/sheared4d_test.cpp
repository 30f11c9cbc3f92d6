// The brute-force 4D sheared filter on light fields built in memory: the closed form of a
// field of one slope (and the sign of the shear), the skipped and fallback pixels, the
// rejection of neighbours across geometry edges, all-zero weights and thread counts.
#include "filters/lightfield/sheared4d.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lightfield_testutil.h"

namespace mcr {
namespace {

using testutil::make_lightfield;

constexpr double kA = 0.5, kB = 0.3, kC = 0.2, kK1 = 7, kK2 = 5;

// One slope s everywhere (dof axes, x units = pixels): f = A + B sin(k1 (y1 + X1/s)) + C cos(k2
// (y2 + X2/s)), constant along the lines the convention shears along. L = 1 = 5 sigma_y and
// max_width/2 / |s| <= 0.2: every displaced sample's y + d/s still covers the Gaussian.
LightField one_slope(float s, int size, int l, unsigned seed) {
  LightField lf = make_lightfield(LightFieldEffect::Dof, size, size, l, 1.0f, 0.2f, false);
  testutil::jitter_samples(lf, seed);
  testutil::set_slopes(lf, s, s);
  testutil::fill_values(lf, [s](double X1, double X2, double y1, double y2) {
    return kA + kB * std::sin(kK1 * (y1 + X1 / s)) + kC * std::cos(kK2 * (y2 + X2 / s));
  });
  return lf;
}

// h(X) = A + B exp(-k1^2 sy^2 / 2) sin(k1 X1 / s) + C exp(-k2^2 sy^2 / 2) cos(k2 X2 / s).
Image one_slope_exact(const LightField& lf, float s) {
  Image out(lf.width, lf.height, 3);
  const double sy = lf.sigma_y;
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double X1, X2;
    testutil::x_units(lf, p, &X1, &X2);
    const double v = kA + kB * std::exp(-kK1 * kK1 * sy * sy / 2) * std::sin(kK1 * X1 / s) +
                     kC * std::exp(-kK2 * kK2 * sy * sy / 2) * std::cos(kK2 * X2 / s);
    out.data()[p * 3] = float(v);
    out.data()[p * 3 + 1] = float(0.8 * v);
    out.data()[p * 3 + 2] = float(0.6 * v);
  }
  return out;
}

Image run4d(const LightField& lf, const lf::Options& o, int nthreads = 0, lf::Counts* c = nullptr) {
  Image out(lf.width, lf.height, 3);
  sheared4d_lightfield(lf, o, Roi::all(lf.width, lf.height), nthreads, out, c);
  return out;
}

lf::Options opts(int max_width) {
  lf::Options o;
  o.max_width = max_width;
  return o;
}

TEST(Sheared4d, OneSlopeFieldMatchesItsClosedForm) {
  const float s = 40;
  const LightField lf = one_slope(s, 40, 6, 1);
  const Image exact = one_slope_exact(lf, s);
  const double own = testutil::rms_diff(exact, testutil::plain_mean(lf));
  const double err = testutil::rms_diff(exact, run4d(lf, opts(16)));
  std::printf("closed form: per-pixel mean %.5f, sheared4d %.5f\n", own, err);
  EXPECT_LT(err, 0.01);
  EXPECT_LT(err, own / 8);
}

TEST(Sheared4d, ShearSignMatters) {
  // The same samples with the bounds' sign flipped shear the other way: the closed form is lost.
  const float s = 40;
  LightField lf = one_slope(s, 40, 6, 2);
  const Image exact = one_slope_exact(lf, s);
  const double right = testutil::rms_diff(exact, run4d(lf, opts(16)));
  testutil::set_slopes(lf, -s, -s);
  const double wrong = testutil::rms_diff(exact, run4d(lf, opts(16)));
  std::printf("eta sign: right %.5f, flipped %.5f\n", right, wrong);
  EXPECT_GT(wrong, 0.05);
  EXPECT_GT(wrong, 8 * right);
}

}  // namespace
}  // namespace mcr
