// The variance of a light-field pixel's own estimate (kernels/lightfield_variance.h) against
// closed forms: chequerboard halves of the strata that disagree by 2 give (2)^2 / 4 = 1, the
// samples' spread is their variance over n; one sample a pixel has none (-1).
#include <gtest/gtest.h>

#include <cmath>

#include "kernels/lightfield_variance.h"
#include "lightfield_testutil.h"

namespace mcr::lf {
namespace {

using testutil::make_lightfield;

int stratum_of(float y, float L, int l) { return std::min(l - 1, int(std::floor((y + L) / (2 * L) * float(l)))); }

TEST(LightFieldVariance, ChequerboardHalvesThatDisagreeByTwoHaveVarianceOne) {
  for (LightFieldEffect e : {LightFieldEffect::SoftShadows, LightFieldEffect::Gi}) {
    SCOPED_TRACE(effect_name(e));
    LightField lf = make_lightfield(e, 6, 5, 4, 1.0f, 0.5f, false);
    testutil::jitter_samples(lf, 3);
    for (std::size_t k = 0; k < lf.samples(); ++k) {
      const int h = (stratum_of(lf.y1[k], 1.0f, 4) + stratum_of(lf.y2[k], 1.0f, 4)) & 1;
      lf.r[k] = h ? 1.0f : -1.0f;
      lf.g[k] = 2.0f;  // the same in every sample: no variance
      lf.b[k] = h ? 0.5f : 0.0f;
    }
    const Image v = estimate_variance(lf, VarianceFrom::Strata, Roi{0, 0, 6, 5}, 2);
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 6; ++x) {
        EXPECT_NEAR(v.at(x, y, 0), 1.0, 1e-6);
        EXPECT_NEAR(v.at(x, y, 1), 0.0, 1e-9);
        EXPECT_NEAR(v.at(x, y, 2), 0.0625, 1e-7);
      }
  }
}

TEST(LightFieldVariance, TheSamplesSpreadOverTheirCount) {
  // gi weighs every sample inside [-L, L]^2 alike: the variance of the plain mean of n
  // independent samples, s^2 / n with s^2 the unbiased sample variance.
  LightField lf = make_lightfield(LightFieldEffect::Gi, 3, 2, 3, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 9);
  for (std::size_t k = 0; k < lf.samples(); ++k) {
    lf.r[k] = float((k * 7919) % 13) / 13.0f;
    lf.g[k] = lf.b[k] = 0.0f;
  }
  const Image v = estimate_variance(lf, VarianceFrom::Samples, Roi{0, 0, 3, 2}, 1);
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double m = 0, s2 = 0;
    for (int k = 0; k < 9; ++k) m += lf.r[p * 9 + std::size_t(k)] / 9.0;
    for (int k = 0; k < 9; ++k) s2 += std::pow(lf.r[p * 9 + std::size_t(k)] - m, 2) / 8.0;
    EXPECT_NEAR(v.data()[p * 3], s2 / 9.0, 1e-7) << "pixel " << p;
    EXPECT_EQ(v.data()[p * 3 + 1], 0.0f);
  }
}

TEST(LightFieldVariance, OneSampleAPixelAndPixelsOutsideTheRegionHaveNone) {
  LightField one = make_lightfield(LightFieldEffect::SoftShadows, 4, 4, 1, 1.0f, 0.5f, false);
  const Image none = estimate_variance(one, VarianceFrom::Strata, Roi{0, 0, 4, 4}, 1);
  for (float x : none.storage()) EXPECT_EQ(x, -1.0f);
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 4, 4, 2, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 1);
  const Image v = estimate_variance(lf, VarianceFrom::Samples, Roi{1, 1, 3, 3}, 1);
  EXPECT_EQ(v.at(0, 0, 0), -1.0f);
  EXPECT_EQ(v.at(1, 1, 0), 0.0f);  // all samples 0
}

}  // namespace
}  // namespace mcr::lf
