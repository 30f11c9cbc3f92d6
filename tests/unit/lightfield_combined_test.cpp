// Soft shadows through a lens (Yan et al. 2015, appendix): the generator's combined scene, its
// file form (the lens half beside the light's), and the two-stage filtering against a closed
// form, the brute-force filter and a converged render.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "expect_error.h"
#include "filters/registry.h"
#include "generator.h"
#include "image/lightfield.h"
#include "io/deep_writer.h"
#include "io/frame_reader.h"
#include "lightfield_testutil.h"

namespace mcr {
namespace {

namespace fs = std::filesystem;
using Settings = std::vector<std::pair<std::string, std::string>>;

class LightFieldCombined : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("mcrecon_lfcomb_" + std::to_string(::getpid()) + "_" + testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Written and read back as a user's file.
  Frame as_file(const LightField& lf) {
    const std::string f = (dir_ / "lf.exr").string();
    write_deep_samples(encode_lightfield(lf), f);
    return read_frame(f);
  }
  static Image run(const Frame& frame, const std::string& filter, const Settings& sets = {}) {
    auto flt = make_filter(filter);
    for (const auto& [k, v] : sets) flt->set_text(k, v);
    flt->commit();
    return flt->execute(frame);
  }
  fs::path dir_;
};

double gaussian(double v, double sigma) { return std::exp(-v * v / (2 * sigma * sigma)); }

std::vector<float> rgb_of(const Image& img) {
  std::vector<float> v;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      for (int c = 0; c < 3; ++c) v.push_back(img.at(x, y, c));
  return v;
}

double relmse(const std::vector<float>& ref, const Image& img) {
  const std::vector<float> got = rgb_of(img);
  double s = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double d = double(got[i]) - double(ref[i]);
    s += d * d / (double(ref[i]) * double(ref[i]) + 0.01);
  }
  return s / double(ref.size());
}

TEST_F(LightFieldCombined, SamplesAreStratifiedOnTheLensAndOnTheLight) {
  const auto gen = lfgen::make_scene("soft_shadows_dof", 12, 10);
  const int l = 4;
  const LightField lf = lfgen::render_lightfield(*gen, l, 9, 0);
  ASSERT_TRUE(lf.combined());
  const LightField& lens = *lf.lens;
  EXPECT_EQ(lf.effect, LightFieldEffect::SoftShadows);
  EXPECT_EQ(lens.effect, LightFieldEffect::Dof);
  EXPECT_TRUE(lf.has_modulation());
  EXPECT_FLOAT_EQ(lens.y_range, 1.f);
  EXPECT_FLOAT_EQ(lens.sigma_y, 0.5f);
  const double L = lf.y_range, cell = 2 * L / l, lens_cell = 2.0 / l;
  for (std::size_t p = 0; p < lf.pixels(); ++p) {
    const std::size_t k0 = p * l * l;
    // The lens: the dof scene's grid, one jitter, stratum (i, j) at sample i + l j.
    const double u1 = (lens.y1[k0] + 1) / lens_cell, u2 = (lens.y2[k0] + 1) / lens_cell;
    // The light: every stratum once, shuffled over the lens strata, one jitter of its own.
    const double o1 = std::fmod((lf.y1[k0] + L) / cell, 1.0), o2 = std::fmod((lf.y2[k0] + L) / cell, 1.0);
    std::vector<int> strata;
    for (int j = 0; j < l; ++j)
      for (int i = 0; i < l; ++i) {
        const std::size_t k = k0 + std::size_t(i + l * j);
        EXPECT_NEAR(lens.y1[k], -1 + (i + u1) * lens_cell, 1e-5) << "pixel " << p;
        EXPECT_NEAR(lens.y2[k], -1 + (j + u2) * lens_cell, 1e-5) << "pixel " << p;
        const double a = (lf.y1[k] + L) / cell, b = (lf.y2[k] + L) / cell;
        EXPECT_NEAR(a - std::floor(a), o1, 1e-4) << "pixel " << p;
        EXPECT_NEAR(b - std::floor(b), o2, 1e-4) << "pixel " << p;
        strata.push_back(int(std::floor(a)) + l * int(std::floor(b)));
        // The value is the texture times the light: never light where the texture is black.
        if (lens.r[k] == 0) EXPECT_EQ(lf.r[k], 0.f);
      }
    std::sort(strata.begin(), strata.end());
    for (int s = 0; s < l * l; ++s) EXPECT_EQ(strata[std::size_t(s)], s) << "pixel " << p;
    EXPECT_LE(lens.smin[p], lens.smax[p]);
  }
  EXPECT_EQ(lfgen::render_reference(*gen, 4, 5, 1), lfgen::render_reference(*gen, 4, 5, 2));
}

TEST_F(LightFieldCombined, TheFileKeepsTheLensAndTheEstimateWeighsLightAndAperture) {
  const auto gen = lfgen::make_scene("soft_shadows_dof", 6, 5);
  const LightField a = lfgen::render_lightfield(*gen, 3, 4, 1);
  const DeepSamples d = encode_lightfield(a);
  EXPECT_EQ(d.attributes.at("mcrecon:lightfield"), "soft_shadows+dof");
  const Frame frame = as_file(a);
  const LightField b = decode_lightfield(*frame.deep, "lf.exr");
  ASSERT_TRUE(b.combined());
  EXPECT_EQ(lightfield_kind(b), "soft_shadows+dof");
  EXPECT_EQ(b.r, a.r);
  EXPECT_EQ(b.y1, a.y1);
  EXPECT_EQ(b.mod_g, a.mod_g);
  EXPECT_EQ(b.lens->r, a.lens->r);
  EXPECT_EQ(b.lens->b, a.lens->b);
  EXPECT_EQ(b.lens->y1, a.lens->y1);
  EXPECT_EQ(b.lens->y2, a.lens->y2);
  EXPECT_EQ(b.lens->smin, a.lens->smin);
  EXPECT_EQ(b.lens->smax, a.lens->smax);
  EXPECT_FLOAT_EQ(b.lens->y_range, a.lens->y_range);
  EXPECT_FLOAT_EQ(b.lens->sigma_y, a.lens->sigma_y);
  // The flat colour every image filter reads: samples weighted by the light and the aperture.
  const Image& colour = frame.image(Role::Colour);
  for (std::size_t p = 0; p < a.pixels(); ++p) {
    double s = 0, w = 0;
    for (std::size_t k = p * 9; k < (p + 1) * 9; ++k) {
      const double wk = gaussian(a.y1[k], a.sigma_y) * gaussian(a.y2[k], a.sigma_y) *
                        gaussian(a.lens->y1[k], a.lens->sigma_y) * gaussian(a.lens->y2[k], a.lens->sigma_y);
      s += wk * a.g[k], w += wk;
    }
    EXPECT_NEAR(colour.at(int(p % 6), int(p / 6), 1), s / w, 1e-5 * (1 + s / w)) << "pixel " << p;
  }
}

TEST_F(LightFieldCombined, BadLensInputIsRefusedByName) {
  const auto gen = lfgen::make_scene("soft_shadows_dof", 4, 3);
  const DeepSamples good = encode_lightfield(lfgen::render_lightfield(*gen, 2, 1, 1));
  {
    DeepSamples d = good;
    const int c = d.channel("lf.u1");
    d.channel_names.erase(d.channel_names.begin() + c);
    d.values.erase(d.values.begin() + c);
    testutil::expect_error(Errc::MissingPass, {"'lf.exr'", "lf.u1", "lens"}, [&] { decode_lightfield(d, "lf.exr"); });
  }
  {
    DeepSamples d = good;
    d.values[std::size_t(d.channel("lf.u2"))][5] = 1.5f;
    testutil::expect_error(Errc::ReadFailed, {"'lf.exr'", "lf.u1, lf.u2", "1.5", "mcrecon:lf_u_range"},
                           [&] { decode_lightfield(d, "lf.exr"); });
  }
  {
    DeepSamples d = good;
    for (std::size_t k = 0; k < 4; ++k) d.values[std::size_t(d.channel("lf.dmin"))][k] = 9.f;  // pixel (0, 0)
    testutil::expect_error(Errc::ReadFailed, {"'lf.exr'", "pixel (0, 0)", "lf.dmin = 9"}, [&] { decode_lightfield(d, "lf.exr"); });
  }
  {
    DeepSamples d = good;
    d.attributes.erase("mcrecon:lf_sigma_u");
    testutil::expect_error(Errc::MissingPass, {"'lf.exr'", "mcrecon:lf_sigma_u"}, [&] { decode_lightfield(d, "lf.exr"); });
  }
  {
    DeepSamples d = good;
    d.values[std::size_t(d.channel("lf.kG"))][2] = std::nanf("");
    std::size_t repaired = 0;
    const LightField lf = decode_lightfield(d, "lf.exr", &repaired);
    EXPECT_EQ(repaired, 1u);
    EXPECT_TRUE(std::isfinite(lf.lens->g[2]));
  }
}

// Each pixel's lens points meet two surfaces (a silhouette): half its samples a lit white one,
// half a dark one (texture 0.2) in shadow, nothing to shear anywhere, weights all but flat. The
// pixel is then its own estimate, mean(t F) = 0.5, with lens_light=sample; the appendix's rule (each
// sample takes its pixel's light, the default) gives mean(t) mean(F) = 0.3, which the closing step
// back (off here) pulls toward the pixel's own estimate.
TEST_F(LightFieldCombined, ASilhouetteKeepsEachSurfacesLight) {
  const int l = 2;
  LightField lf = testutil::make_lightfield(LightFieldEffect::SoftShadows, 6, 4, l, 1.0f, 1e3f, false);
  auto lens = std::make_shared<LightField>(testutil::make_lightfield(LightFieldEffect::Dof, 6, 4, l, 1.0f, 1e3f, false));
  testutil::jitter_samples(lf, 3);
  testutil::jitter_samples(*lens, 4);
  for (std::size_t k = 0; k < lf.samples(); ++k) {
    const bool lit = k % 2 == 0;
    const float t = lit ? 1.0f : 0.2f, f = lit ? 1.0f : 0.0f;
    lens->r[k] = lens->g[k] = lens->b[k] = t;
    lf.r[k] = lf.g[k] = lf.b[k] = t * f;
  }
  lf.lens = lens;
  const Frame frame = as_file(lf);
  for (const char* filter : {"sheared", "sheared4d", "aaf"}) {
    const Image got = run(frame, filter, {{"step_back", "off"}, {"lens_light", "sample"}});
    const Image appendix = run(frame, filter, {{"step_back", "off"}});
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 6; ++x) {
        EXPECT_NEAR(got.at(x, y, 0), 0.5f, 1e-4) << filter << " pixel " << x << "," << y;
        EXPECT_NEAR(appendix.at(x, y, 0), 0.3f, 1e-4) << filter << " pixel " << x << "," << y;
      }
  }
}

// The factored filter against the brute-force one (eq. 9), both run in the two stages, and both
// against the converged render: better than the pixels' own estimates at 16 and 64 samples.
TEST_F(LightFieldCombined, TheTwoStagesMatchTheBruteForceFilterAndBeatTheInput) {
  const auto gen = lfgen::make_scene("soft_shadows_dof", 64, 64);
  const std::vector<float> ref = lfgen::render_reference(*gen, 24, 2, 2);
  for (const int l : {4, 8}) {
    const Frame frame = as_file(lfgen::render_lightfield(*gen, l, 1, 2));
    const double input = relmse(ref, frame.image(Role::Colour));
    const Image fast = run(frame, "sheared");
    const double sheared = relmse(ref, fast);
    const double brute = relmse(rgb_of(run(frame, "sheared4d")), fast);
    std::printf("soft shadows through a lens, %d spp: input %.3g, sheared %.3g, sheared against sheared4d %.3g\n", l * l,
                input, sheared, brute);
    EXPECT_LT(sheared, 0.8 * input) << l * l << " spp";
    EXPECT_LT(brute, 0.01) << l * l << " spp";
  }
}

}  // namespace
}  // namespace mcr
