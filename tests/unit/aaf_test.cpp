// Axis-aligned filtering of light fields: on a field of one slope it integrates each pixel
// over y (the damped sinusoid of the closed form) and then blurs that sinusoid by its Gaussian:
// the attenuation is the Gaussian's transfer at the sinusoid's frequency (the finite sum over
// the support, close to exp(-omega^2 sigma^2 / 2)), with sigma_x = sigma_y |s| / (2 mu).
#include "filters/lightfield/aaf.h"

#include <gtest/gtest.h>

#include <cmath>

#include "lightfield_testutil.h"

namespace mcr {
namespace {

constexpr double kA = 0.5, kB = 0.3, kC = 0.2, kK1 = 7, kK2 = 5;

// The normalised Gaussian of sigma (pixels) over j = -r..r, at frequency omega (rad / pixel).
double transfer(double omega, double sigma, int r) {
  double s = 0, c = 0;
  for (int j = -r; j <= r; ++j) {
    const double w = std::exp(-double(j * j) / (2 * sigma * sigma));
    s += w;
    c += w * std::cos(omega * j);
  }
  return c / s;
}

// f = A + B sin(k1 (y1 + X1/s)) + C cos(k2 (y2 + X2/s)) (dof axes); the expected output with
// the y-integral's damping D_i = exp(-k_i^2 sigma_y^2 / 2) and the blur's T_i per axis.
Image expected(const LightField& lf, double s, double t1, double t2) {
  Image out(lf.width, lf.height, 3);
  const double sy = lf.sigma_y;
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double X1, X2;
    testutil::x_units(lf, p, &X1, &X2);
    const double v = kA + kB * std::exp(-kK1 * kK1 * sy * sy / 2) * t1 * std::sin(kK1 * X1 / s) +
                     kC * std::exp(-kK2 * kK2 * sy * sy / 2) * t2 * std::cos(kK2 * X2 / s);
    for (int c = 0; c < 3; ++c) out.data()[p * 3 + std::size_t(c)] = float(v * (1.0 - 0.2 * c));
  }
  return out;
}

TEST(Aaf, BlursTheIntegratedSinusoidByItsGaussian) {
  const float s = 40;
  LightField lf = testutil::make_lightfield(LightFieldEffect::Dof, 64, 64, 6, 1.0f, 0.2f, false);
  testutil::jitter_samples(lf, 5);
  testutil::set_slopes(lf, s, s);
  testutil::fill_values(lf, [s](double X1, double X2, double y1, double y2) {
    return kA + kB * std::sin(kK1 * (y1 + X1 / s)) + kC * std::cos(kK2 * (y2 + X2 / s));
  });
  lf::Options o;
  o.mu = 0.5f;
  o.max_width = 32;
  const double sigma = 0.2 * 40 / (2 * 0.5);  // sigma_y |s| / (2 mu) = 8 pixels (dof: x units are pixels)
  const int r = 16;                            // min(ceil(2 sigma), max_width / 2)
  Image out(lf.width, lf.height, 3);
  aaf_lightfield(lf, o, Roi::all(64, 64), 0, out, nullptr);
  const double t1 = transfer(kK1 / s, sigma, r), t2 = transfer(kK2 / s, sigma, r);
  EXPECT_NEAR(t1, std::exp(-std::pow(kK1 / s * sigma, 2) / 2), 0.1);
  const double blurred = testutil::rms_diff(expected(lf, s, t1, t2), out, r);
  const double unblurred = testutil::rms_diff(expected(lf, s, 1, 1), out, r);
  const double own = testutil::rms_diff(expected(lf, s, 1, 1), testutil::plain_mean(lf), r);
  std::printf("aaf: T1 %.4f T2 %.4f, against blurred %.5f, unblurred %.5f (own means %.4f)\n", t1, t2, blurred,
              unblurred, own);
  EXPECT_LT(blurred, 0.006);
  EXPECT_GT(unblurred, 5 * blurred);
}

}  // namespace
}  // namespace mcr
