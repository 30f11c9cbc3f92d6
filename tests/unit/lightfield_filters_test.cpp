// What the three light-field filters (sheared4d, sheared, aaf) share: the skipped, converged and
// fallback pixels and their counts, the slope smoothing, the rejection of neighbours across a
// normal or depth edge, all-zero weights, thread counts, and the Filter wrappers' refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "expect_error.h"
#include "filters/lightfield/aaf.h"
#include "filters/lightfield/sheared.h"
#include "filters/lightfield/sheared4d.h"
#include "filters/registry.h"
#include "lightfield_testutil.h"
#include "util/error.h"

namespace mcr {
namespace {

using testutil::make_lightfield;
using Run = std::function<void(const LightField&, const lf::Options&, const Roi&, int, Image&, lf::Counts*)>;

struct Named {
  const char* name;
  Run run;
  bool sheared;
};

const std::vector<Named>& filters() {
  static const std::vector<Named> list = {{"sheared4d", sheared4d_lightfield, true},
                                          {"sheared", sheared_lightfield, true},
                                          {"aaf", aaf_lightfield, false}};
  return list;
}

Image run(const Named& f, const LightField& lf, const lf::Options& o, int nthreads = 0, lf::Counts* c = nullptr) {
  Image out(lf.width, lf.height, 3);
  f.run(lf, o, Roi::all(lf.width, lf.height), nthreads, out, c);
  return out;
}

void random_values(LightField& lf, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (std::size_t k = 0; k < lf.samples(); ++k) {
    lf.r[k] = u(rng);
    lf.g[k] = u(rng) < 0.5f ? 0.1f : 0.9f;
    lf.b[k] = 0.5f;
  }
}

// The pixel's own sum f w_y(y1) w_y(y2) / sum w_y, Gaussian w_y.
double own_gauss_mean(const LightField& lf, std::size_t p, int ch) {
  const std::vector<float>& v = ch == 0 ? lf.r : ch == 1 ? lf.g : lf.b;
  double s = 0, ws = 0;
  for (std::size_t k = p * std::size_t(lf.spp()); k < (p + 1) * std::size_t(lf.spp()); ++k) {
    const double w = std::exp(-(double(lf.y1[k]) * lf.y1[k] + double(lf.y2[k]) * lf.y2[k]) /
                              (2.0 * lf.sigma_y * lf.sigma_y));
    s += w * v[k];
    ws += w;
  }
  return s / ws;
}

// 20 x 20 soft shadows: columns 0..5 bounds (2, 3); (15, 15) bounds (-1, 2); (15, 3) bounds
// (0, 2); the rest 0. With the 5x5 smoothing: columns 6, 7 take (2, 3) (40 pixels), the 24
// around (15, 15) take (-1, 2), the 24 around (15, 3) take (0, 2): 120 + 40 sheared, 50
// fallback (2 + 48 smoothed), 190 with nothing to shear. (2, 2) is converged.
LightField counting_field() {
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 20, 20, 2, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 7);
  random_values(lf, 8);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 6; ++x) {
      lf.smin[std::size_t(y * 20 + x)] = 2;
      lf.smax[std::size_t(y * 20 + x)] = 3;
    }
  lf.smin[15 * 20 + 15] = -1;
  lf.smax[15 * 20 + 15] = 2;
  lf.smin[3 * 20 + 15] = 0;
  lf.smax[3 * 20 + 15] = 2;
  // Converged: the samples of (2, 2) and of its 8 neighbours agree. (4, 12) agrees with itself
  // alone (4 samples can, by chance): not converged.
  for (int y = 1; y <= 3; ++y)
    for (int x = 1; x <= 3; ++x)
      for (std::size_t k = std::size_t(y * 20 + x) * 4; k < std::size_t(y * 20 + x + 1) * 4; ++k) {
        lf.r[k] = 0.25f;
        lf.g[k] = 0.5f;
        lf.b[k] = 0.75f;
      }
  for (std::size_t k = std::size_t(12 * 20 + 4) * 4; k < std::size_t(12 * 20 + 5) * 4; ++k) lf.r[k] = lf.g[k] = lf.b[k] = 2.0f;
  return lf;
}

TEST(LightFieldFilters, CountsSkippedFallbackConvergedAndSmoothedPixels) {
  const LightField lf = counting_field();
  for (const Named& f : filters()) {
    lf::Counts c;
    const Image out = run(f, lf, lf::Options{}, 0, &c);
    EXPECT_EQ(c.pixels, 400u) << f.name;
    EXPECT_EQ(c.own, 190u) << f.name;
    EXPECT_EQ(c.fallback, f.sheared ? 50u : 0u) << f.name;
    EXPECT_EQ(c.converged, 1u) << f.name;
    EXPECT_EQ(c.smoothed, 88u) << f.name;
    EXPECT_EQ(c.zero_weight, 0u) << f.name;
    const std::string want = std::string(f.name) + ": 190 of 400 pixels had nothing to " +
                             (f.sheared ? "shear (own samples), 50 axis-aligned fallback" : "filter (own samples)") +
                             ", 1 converged (own samples), 88 took smoothed slope bounds";
    EXPECT_EQ(lf::counts_note(f.name, c, f.sheared), want);
    // A pixel with nothing to shear is its own w_y-weighted mean; the converged one its value.
    for (std::size_t p : {std::size_t(10 * 20 + 12), std::size_t(19 * 20 + 19), std::size_t(8 * 20 + 10)})
      for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(out.data()[p * 3 + std::size_t(ch)], own_gauss_mean(lf, p, ch), 1e-5) << f.name << " " << p;
    EXPECT_EQ(out.at(2, 2, 0), 0.25f) << f.name;
    EXPECT_EQ(out.at(2, 2, 2), 0.75f) << f.name;
    EXPECT_LT(out.at(4, 12, 0), 1.9f) << f.name << ": a pixel whose own samples alone agree is filtered";
    // Filtered pixels are not their own mean.
    EXPECT_GT(std::fabs(out.at(3, 10, 0) - own_gauss_mean(lf, 10 * 20 + 3, 0)), 1e-3) << f.name;
  }
  lf::Options o;
  o.smooth_radius = 0;
  lf::Counts c;
  run(filters()[1], lf, o, 0, &c);
  EXPECT_EQ(c.own, 278u);
  EXPECT_EQ(c.fallback, 2u);
  EXPECT_EQ(c.smoothed, 0u);
  o = lf::Options{};
  o.fallback_aaf = false;  // fallback pixels keep their own mean
  const Image own_fb = run(filters()[1], lf, o, 0, &c);
  EXPECT_EQ(c.fallback, 50u);
  EXPECT_NEAR(own_fb.at(15, 15, 0), own_gauss_mean(lf, 15 * 20 + 15, 0), 1e-5);
}

TEST(LightFieldFilters, SmoothingIsForSoftShadowsOnly) {
  LightField lf = counting_field();
  lf.effect = LightFieldEffect::Dof;
  lf::Counts c;
  run(filters()[0], lf, lf::Options{}, 0, &c);
  EXPECT_EQ(c.smoothed, 0u);
  EXPECT_EQ(c.own, 278u);
}

// 24 x 24 soft shadows on the plane z = 0, 2 pixels per world unit, every normal +z.
LightField plane_field(unsigned seed) {
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 24, 24, 3, 1.0f, 0.5f, true);
  testutil::jitter_samples(lf, seed);
  testutil::set_axes(lf, 2, 0, 0, 2);
  testutil::set_slopes(lf, 2, 3);
  random_values(lf, seed + 1);
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) {
      const std::size_t p = std::size_t(y * 24 + x);
      lf.px[p] = (float(x) + 0.5f) / 2;
      lf.py[p] = (float(y) + 0.5f) / 2;
    }
  return lf;
}

// Whether any pixel but q changes when q's sample values change.
bool others_depend_on(const Named& f, const LightField& lf, std::size_t q) {
  const Image a = run(f, lf, lf::Options{});
  LightField changed = lf;
  for (std::size_t k = q * std::size_t(lf.spp()); k < (q + 1) * std::size_t(lf.spp()); ++k) {
    changed.r[k] = 5 * changed.r[k] + 3;
    changed.g[k] = 0;
  }
  const Image b = run(f, changed, lf::Options{});
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    if (p == q) continue;
    for (int ch = 0; ch < 3; ++ch)
      if (a.data()[p * 3 + std::size_t(ch)] != b.data()[p * 3 + std::size_t(ch)]) return true;
  }
  return false;
}

TEST(LightFieldFilters, RejectsANeighbourAcrossANormalEdge) {
  const std::size_t q = 12 * 24 + 12;
  for (const Named& f : filters()) {
    LightField lf = plane_field(3);
    EXPECT_TRUE(others_depend_on(f, lf, q)) << f.name << ": the control";
    lf.nx[q] = 1;  // 90 degrees
    lf.nz[q] = 0;
    EXPECT_FALSE(others_depend_on(f, lf, q)) << f.name;
    lf.nx[q] = std::sin(0.3f);  // 17 degrees: kept
    lf.nz[q] = std::cos(0.3f);
    EXPECT_TRUE(others_depend_on(f, lf, q)) << f.name;
  }
}

TEST(LightFieldFilters, RejectsANeighbourAcrossADepthJump) {
  const std::size_t q = 12 * 24 + 12;
  for (const Named& f : filters()) {
    LightField lf = plane_field(4);
    lf.pz[q] = 40;  // far above the plane: beyond 2 |d| + one pixel for every d in the window
    EXPECT_FALSE(others_depend_on(f, lf, q)) << f.name;
    lf.pz[q] = 0.2f;  // within one pixel's world size (0.5) of the plane: kept
    EXPECT_TRUE(others_depend_on(f, lf, q)) << f.name;
    lf.pz[q] = 40;
    lf.effect = LightFieldEffect::Dof;  // no rejection for depth of field
    EXPECT_TRUE(others_depend_on(f, lf, q)) << f.name;
  }
}

TEST(LightFieldFilters, AllZeroWeightsGiveTheOwnMean) {
  // gi's box over y: every sample far outside [-L, L] (however sheared) weighs 0.
  LightField lf = make_lightfield(LightFieldEffect::Gi, 12, 10, 2, 1.0f, 0.7f, false);
  testutil::jitter_samples(lf, 9);
  random_values(lf, 10);
  testutil::set_slopes(lf, 1, 2);
  for (float& v : lf.y1) v += 100;
  const Image plain = testutil::plain_mean(lf);
  for (const Named& f : filters()) {
    lf::Counts c;
    const Image out = run(f, lf, lf::Options{}, 0, &c);
    for (float v : out.storage()) ASSERT_TRUE(std::isfinite(v)) << f.name;
    if (!f.sheared) continue;  // aaf's spatial weights never vanish: it blurs the plain means
    EXPECT_EQ(c.zero_weight, lf.pixels()) << f.name;
    EXPECT_LT(testutil::rms_diff(out, plain), 1e-6) << f.name;
  }
}

TEST(LightFieldFilters, SameBitsOnAnyThreadCount) {
  LightField lf = make_lightfield(LightFieldEffect::SoftShadows, 37, 29, 3, 1.0f, 0.5f, true);
  testutil::jitter_samples(lf, 11);
  random_values(lf, 12);
  testutil::set_axes(lf, 1.3f, 0.5f, -0.4f, 1.1f);
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-1.0f, 4.0f);
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    const float a = u(rng), b = u(rng);
    lf.smin[p] = a < 0.3f && a > -0.3f ? 0.0f : std::min(a, b);
    lf.smax[p] = a < 0.3f && a > -0.3f ? 0.0f : std::max(a, b);
    lf.nz[p] = 1;
    lf.pz[p] = u(rng) > 3.5f ? 2.0f : 0.0f;
  }
  for (const Named& f : filters()) {
    const Image one = run(f, lf, lf::Options{}, 1), two = run(f, lf, lf::Options{}, 2);
    EXPECT_TRUE(testutil::same_bits(one, two)) << f.name;
  }
}

TEST(LightFieldFilters, WritesOnlyTheRoi) {
  LightField lf = make_lightfield(LightFieldEffect::Dof, 30, 20, 2, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 14);
  random_values(lf, 15);
  testutil::set_slopes(lf, 1, 3);
  const Roi roi{5, 4, 21, 13};
  for (const Named& f : filters()) {
    const Image full = run(f, lf, lf::Options{});
    Image part(30, 20, 3, -1.0f);
    f.run(lf, lf::Options{}, roi, 0, part, nullptr);
    for (int y = 0; y < 20; ++y)
      for (int x = 0; x < 30; ++x)
        for (int ch = 0; ch < 3; ++ch) {
          if (roi.contains(x, y))
            EXPECT_EQ(part.at(x, y, ch), full.at(x, y, ch)) << f.name << " " << x << "," << y;
          else
            EXPECT_EQ(part.at(x, y, ch), -1.0f) << f.name;
        }
  }
}

Frame flat_frame() {
  Frame fr;
  fr.width = 4;
  fr.height = 3;
  fr.path = "flat.exr";
  Pass p;
  p.role = Role::Colour;
  p.name = "Combined";
  p.image = Image(4, 3, 3, 0.5f);
  fr.passes.push_back(p);
  return fr;
}

TEST(LightFieldFilters, WrappersRefuseFramesWithoutALightField) {
  for (const char* name : {"sheared", "sheared4d", "aaf"}) {
    std::unique_ptr<Filter> f = make_filter(name);
    EXPECT_TRUE(f->info().deep_input);
    for (const ParamSpec& s : f->info().params) EXPECT_FALSE(s.help.empty()) << name << " " << s.name;
    EXPECT_FALSE(f->info().nonfinite_policy.empty());
    f->commit();
    Frame fr = flat_frame();
    testutil::expect_error(Errc::MissingPass, {name, "light-field deep EXR", "flat.exr"},
                           [&] { f->execute(fr); });
    auto deep = std::make_shared<DeepSamples>();
    deep->width = 4;
    deep->height = 3;
    deep->offsets.assign(13, 0);
    fr.deep = deep;
    testutil::expect_error(Errc::MissingPass, {name, "mcrecon:lightfield", "flat.exr"}, [&] { f->execute(fr); });
  }
}

}  // namespace
}  // namespace mcr
