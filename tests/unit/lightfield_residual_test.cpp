// The light-field filters' residual stage and step back (kernels/lightfield_input.h,
// residual_k, step_back): what a filter's window misplaces is pulled back by the pixels' own
// samples. Oracles: the closed form of a one-slope soft-shadow edge (the light's Gaussian mass
// below the edge), and the generator's soft-shadow scene against its converged render, through
// the file and the Filter wrappers as a user runs them; the defaults by effect and by samples
// against explicit settings.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "filters/registry.h"
#include "io/deep_writer.h"
#include "io/frame_reader.h"
#include "generator.h"
#include "lightfield_testutil.h"

namespace mcr {
namespace {

namespace fs = std::filesystem;
using testutil::make_lightfield;

// A shadow edge of slope 4 (x units = pixels) across the middle of a 64 x 8 receiver: lit where
// y1 + (X1 - 32) / 4 <= 0.2, the Gaussian light (sigma 0.5) on [-1, 1]; 64 samples a pixel.
constexpr double kSlope = 4, kC = 0.2;
LightField edge(LightFieldEffect effect, float declared_slope, int l = 8) {
  LightField lf = make_lightfield(effect, 64, 8, l, 1.0f, 0.5f, false);
  testutil::jitter_samples(lf, 5);
  testutil::set_slopes(lf, declared_slope, declared_slope);
  testutil::fill_values(lf, [](double X1, double, double y1, double y2) {
    return y1 + (X1 - 32) / kSlope <= kC ? 1.0 + 0.05 * y2 : 0.0;
  });
  return lf;
}

double light_mass(double a, double b) {  // the Gaussian (sigma 0.5) over [a, b]
  return 0.5 * (std::erf(b / (0.5 * std::sqrt(2.0))) - std::erf(a / (0.5 * std::sqrt(2.0))));
}

// RMS over the pixels at least 2 from the left and right ends against the closed form.
double rms_against_exact(const LightField& lf, const Image& got) {
  double s = 0;
  int n = 0;
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double X1, X2;
    testutil::x_units(lf, p, &X1, &X2);
    const int x = int(p % std::size_t(lf.width));
    if (x < 2 || x >= lf.width - 2) continue;
    const double top = std::min(1.0, std::max(-1.0, kC - (X1 - 32) / kSlope));
    const double v = light_mass(-1, top) / light_mass(-1, 1);
    const double d = double(got.data()[p * 3]) - v;
    s += d * d;
    ++n;
  }
  return std::sqrt(s / n);
}

class LightFieldResidual : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("mcrecon_lfres_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // The light field written and read back as a user's file, filtered by `filter` with `k`
  // (empty: the default).
  Image run(const LightField& lf, const std::string& filter, const std::string& k, const std::string& radius = "",
            const std::string& step_back = "") {
    const std::string f = (dir_ / "lf.exr").string();
    write_deep_samples(encode_lightfield(lf), f);
    const Frame frame = read_frame(f);
    auto flt = make_filter(filter);
    if (!k.empty()) flt->set_text("residual_k", k);
    if (!radius.empty()) flt->set_text("residual_radius", radius);
    if (!step_back.empty()) flt->set_text("step_back", step_back);
    flt->commit();
    return flt->execute(frame);
  }
  fs::path dir_;
};

TEST_F(LightFieldResidual, AMisplacedShadowEdgeIsPulledBackByTheOwnSamples) {
  // Bounds that say slope 8 where the edge has slope 4: the shear maps the neighbours' samples
  // to the wrong place on the light and the penumbra comes out twice as wide (RMS 0.064); the
  // 64 own samples of each pixel see it where it is (0.021 with them).
  // The step back (on by default for soft shadows) pulls it back too: off here, then both.
  const LightField lf = edge(LightFieldEffect::SoftShadows, 8.0f);
  for (const char* filter : {"sheared", "sheared4d"}) {
    SCOPED_TRACE(filter);
    const double off = rms_against_exact(lf, run(lf, filter, "0", "", "off"));
    const double on = rms_against_exact(lf, run(lf, filter, "", "", "off"));
    const double both = rms_against_exact(lf, run(lf, filter, ""));
    std::printf("%s, misplaced edge: residual off %.4f, on %.4f, with the step back (default) %.4f\n", filter, off,
                on, both);
    EXPECT_GT(off, 0.04);
    EXPECT_LT(on, 0.6 * off);
    EXPECT_LT(both, 0.6 * off);
  }
}

TEST_F(LightFieldResidual, TheDefaultFollowsTheEffect) {
  // dof takes residual_k 3 by default, soft shadows 1 (with the step back after it), gi none.
  for (LightFieldEffect e : {LightFieldEffect::SoftShadows, LightFieldEffect::Dof, LightFieldEffect::Gi}) {
    SCOPED_TRACE(effect_name(e));
    const LightField lf = edge(e, 2.0f);
    const Image def = run(lf, "aaf", ""), off = run(lf, "aaf", "0");
    const char* k = e == LightFieldEffect::SoftShadows ? "1" : "3";
    const Image on = run(lf, "aaf", k), other = run(lf, "aaf", e == LightFieldEffect::SoftShadows ? "3" : "1");
    const bool gi = e == LightFieldEffect::Gi;
    EXPECT_EQ(def.storage(), gi ? off.storage() : on.storage());
    EXPECT_NE(on.storage(), off.storage());
    EXPECT_NE(on.storage(), other.storage());
  }
  // Soft shadows without the step back after it (one sample a pixel, or step_back=off): 3.
  const LightField one = edge(LightFieldEffect::SoftShadows, 2.0f, 1);
  EXPECT_EQ(run(one, "aaf", "").storage(), run(one, "aaf", "3").storage());
  EXPECT_NE(run(one, "aaf", "").storage(), run(one, "aaf", "1").storage());
  const LightField many = edge(LightFieldEffect::SoftShadows, 2.0f);
  EXPECT_EQ(run(many, "aaf", "", "", "off").storage(), run(many, "aaf", "3", "", "off").storage());
}

TEST_F(LightFieldResidual, TheWindowNarrowsWithTheSamples) {
  // 4 samples a pixel: the 5x5 window; 9 and more: 3x3.
  for (int l : {2, 3, 8}) {
    SCOPED_TRACE(l);
    const LightField lf = edge(LightFieldEffect::SoftShadows, 8.0f, l);
    const Image def = run(lf, "aaf", ""), r1 = run(lf, "aaf", "", "1"), r2 = run(lf, "aaf", "", "2");
    EXPECT_NE(r1.storage(), r2.storage());
    EXPECT_EQ(def.storage(), l <= 2 ? r2.storage() : r1.storage());
  }
}

double relmse(const std::vector<float>& ref, const Image& got) {
  double s = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double d = double(got.data()[i]) - ref[i];
    s += d * d / (double(ref[i]) * ref[i] + 0.01);
  }
  return s / double(ref.size());
}

Image own_estimate(const LightField& lf) {  // each pixel's samples weighted by the light
  Image out(lf.width, lf.height, 3);
  const std::size_t n = std::size_t(lf.spp());
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    double s[3] = {0, 0, 0}, sw = 0;
    for (std::size_t k = p * n; k < (p + 1) * n; ++k) {
      const double w = double(lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y1[k])) *
                       lightfield_y_weight(lf.effect, lf.sigma_y, lf.y_range, lf.y2[k]);
      s[0] += w * lf.r[k], s[1] += w * lf.g[k], s[2] += w * lf.b[k], sw += w;
    }
    for (int c = 0; c < 3; ++c) out.data()[p * 3 + std::size_t(c)] = float(s[c] / sw);
  }
  return out;
}

TEST_F(LightFieldResidual, WellSampledSoftShadowsAreNoWorseThanTheirOwnSamples) {
  // The generator's soft shadows at 64 samples a pixel: the filters' windows widen its sharpest
  // contact shadows (a bias more samples do not shrink), so without the step back `sheared` is
  // worse than the pixels' own estimate; with it (the default) it is better.
  const auto gen = lfgen::make_scene("soft_shadows", 128, 128);
  const LightField lf = lfgen::render_lightfield(*gen, 8, 1, 2);
  const std::vector<float> ref = lfgen::render_reference(*gen, 32, 2, 2);
  const double input = relmse(ref, own_estimate(lf));
  const double off = relmse(ref, run(lf, "sheared", "", "", "off"));
  const double on = relmse(ref, run(lf, "sheared", "", "", ""));
  std::printf("soft shadows, 64 spp: input %.3g, sheared with step_back=off %.3g, default %.3g\n", input, off, on);
  EXPECT_GT(off, input);
  EXPECT_LT(on, 0.9 * input);
}

TEST_F(LightFieldResidual, TheStepBackFollowsTheEffect) {
  // Soft shadows step back with the strata's variance by default; dof and gi do not.
  for (LightFieldEffect e : {LightFieldEffect::SoftShadows, LightFieldEffect::Dof, LightFieldEffect::Gi}) {
    SCOPED_TRACE(effect_name(e));
    const LightField lf = edge(e, 8.0f);
    const Image def = run(lf, "sheared", "", "", ""), off = run(lf, "sheared", "", "", "off"),
                strata = run(lf, "sheared", "", "", "strata");
    EXPECT_EQ(def.storage(), e == LightFieldEffect::SoftShadows ? strata.storage() : off.storage());
    EXPECT_NE(strata.storage(), off.storage());
  }
}

}  // namespace
}  // namespace mcr
