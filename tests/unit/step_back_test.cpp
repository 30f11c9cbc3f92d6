// prepare/step_back: the blend toward the input, against images whose truth is known.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "io/frame_reader.h"
#include "prepare/step_back.h"

namespace mcr {
namespace {

// Blocks of 12 px at levels in [0.05, 2] (dark next to bright) plus a ramp; noise sigma
// relative to the level (as Monte Carlo noise roughly is).
Image scene(int w, int h, double rel_sigma, unsigned seed, Image* clean_out = nullptr) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> level(0.05f, 2.0f);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  std::vector<float> lv(std::size_t((w / 12 + 1) * (h / 12 + 1)) * 3);
  for (float& v : lv) v = level(rng);
  Image clean(w, h, 3), noisy(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = lv[std::size_t(((y / 12) * (w / 12 + 1) + x / 12) * 3 + c)] * (1.0f + 0.003f * float(x));
        clean.at(x, y, c) = v;
        noisy.at(x, y, c) = v * (1.0f + float(rel_sigma) * noise(rng));
      }
  if (clean_out) *clean_out = clean;
  return noisy;
}

Image box_blur(const Image& in, int r) { return testutil::box_oracle(in, r); }

double relmse(const Image& a, const Image& ref) { return testutil::relmse_oracle(a, ref); }

TEST(StepBack, ACleanRenderStaysAsItWas) {
  Image clean;
  scene(96, 72, 0.0, 1, &clean);
  const Image blurred = box_blur(clean, 3);
  Image out = blurred;
  step_back(clean, Roi::all(96, 72), 4, 2, out);
  EXPECT_LT(relmse(out, clean), 0.01 * relmse(blurred, clean));
}

TEST(StepBack, TheTruthAsTheResultIsKept) {
  Image clean;
  const Image noisy = scene(96, 72, 0.3, 2, &clean);
  Image out = clean;
  const StepBackStats st = step_back(noisy, Roi::all(96, 72), 4, 2, out);
  EXPECT_LT(relmse(out, clean), 0.2 * relmse(noisy, clean));
  EXPECT_GT(st.mean_weight, 0.8);
}

TEST(StepBack, ABiasedFilterIsNoWorseThanTheInputOrItself) {
  for (double sigma : {0.03, 0.1, 0.3, 1.0}) {
    SCOPED_TRACE(sigma);
    Image clean;
    const Image noisy = scene(96, 72, sigma, 3, &clean);
    const Image blurred = box_blur(noisy, 4);  // averages across every block edge
    Image out = blurred;
    step_back(noisy, Roi::all(96, 72), 4, 2, out);
    EXPECT_LT(relmse(out, clean), relmse(noisy, clean));
    EXPECT_LT(relmse(out, clean), relmse(blurred, clean));
  }
}

// The image's noise estimate spreads around the truth window by window: with the truth as the
// result, windows whose estimate runs low step back toward the noise; twice the estimate keeps it.
TEST(StepBack, TwiceTheNoiseKeepsASoundResultWhereTheEstimateRunsLow) {
  for (double sigma : {0.1, 0.3}) {
    SCOPED_TRACE(sigma);
    Image clean;
    const Image noisy = scene(96, 72, sigma, 7, &clean);
    Image once = clean, twice = clean;
    const StepBackStats s1 = step_back(noisy, Roi::all(96, 72), 4, 2, once, nullptr, 1.0);
    const StepBackStats s2 = step_back(noisy, Roi::all(96, 72), 4, 2, twice, nullptr, 2.0);
    EXPECT_GT(s2.mean_weight, s1.mean_weight);
    EXPECT_LT(relmse(twice, clean), 0.8 * relmse(once, clean));
  }
}

// Stein's risk with the variance scaled by k is s^2 - (2k - k^2) gain: up to k = 2 a biased
// result blended back is still no worse than the input; above 2 the scale is capped.
TEST(StepBack, UpToTwiceTheNoiseABiasedFilterIsNoWorseThanTheInput) {
  for (double sigma : {0.03, 0.1, 0.3, 1.0}) {
    SCOPED_TRACE(sigma);
    Image clean;
    const Image noisy = scene(96, 72, sigma, 3, &clean);
    const Image blurred = box_blur(noisy, 4);
    Image out = blurred, capped = blurred;
    step_back(noisy, Roi::all(96, 72), 4, 2, out, nullptr, 2.0);
    step_back(noisy, Roi::all(96, 72), 4, 2, capped, nullptr, 50.0);
    EXPECT_LT(relmse(out, clean), relmse(noisy, clean));
    EXPECT_LT(relmse(out, clean), relmse(blurred, clean));
    EXPECT_EQ(out.storage(), capped.storage());
  }
}

// bilateral, atrous and pwaf take twice the estimate by default where an albedo pass carries
// texture through, once without, and estimate it on the illumination; the others once, on the
// colour; a value given is kept. With an albedo pass the filter's result is the oracle's blend
// at 2 on the illumination.
TEST(StepBack, TwiceTheNoiseByDefaultOnlyForEdgeKeepingFiltersWithAnAlbedoPass) {
  Image clean;
  const Image noisy = scene(40, 30, 0.2, 9, &clean);
  const Frame plain = testutil::colour_frame(noisy);
  Frame with_albedo = plain;
  testutil::add_pass(with_albedo, Role::Albedo, Image(40, 30, 3, 0.5f));
  for (const std::string& name : image_filter_names()) {
    auto f = make_filter(name);
    if (f->info().temporal) continue;
    SCOPED_TRACE(name);
    const bool keeps = name == "bilateral" || name == "atrous" || name == "pwaf";
    EXPECT_EQ(step_back_noise_for(f->params(), with_albedo), keeps ? 2.0 : 1.0);
    EXPECT_EQ(step_back_noise_for(f->params(), plain), 1.0);
    // ... and estimate the noise on the illumination where an albedo pass exists.
    EXPECT_EQ(step_back_modulation(f->params(), with_albedo), keeps ? &with_albedo.image(Role::Albedo) : nullptr);
    EXPECT_EQ(step_back_modulation(f->params(), plain), nullptr);
    f->set("step_back_noise", 1.5);
    EXPECT_EQ(step_back_noise_for(f->params(), with_albedo), 1.5);
    f->set("step_back_estimate", std::string(keeps ? "colour" : "illumination"));
    EXPECT_EQ(step_back_modulation(f->params(), with_albedo), keeps ? nullptr : &with_albedo.image(Role::Albedo));
  }
  auto on = make_filter("pwaf");
  on->commit();
  const Image a = on->execute(with_albedo);
  auto off = make_filter("pwaf");
  off->set("step_back", false);
  off->commit();
  Image expect = off->execute(with_albedo);
  step_back(noisy, Roi::all(40, 30), 4, 0, expect, nullptr, 2.0, &with_albedo.image(Role::Albedo));
  EXPECT_EQ(a.storage(), expect.storage());
}

// Thin albedo stripes (one pixel in three) under smooth light, noise 1%: each stripe is a
// peak, which the colour's noise estimate reads as noise; divided by the albedo it is flat.
// A blurred result must then be stepped back from nearly everywhere (the input is almost the
// truth), which only the estimate on the illumination does.
TEST(StepBack, TextureTheAlbedoExplainsIsNotReadAsNoise) {
  const int w = 72, h = 54;
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  Image albedo(w, h, 3), clean(w, h, 3), noisy(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        albedo.at(x, y, c) = x % 3 == 0 ? 0.8f : 0.2f;
        clean.at(x, y, c) = albedo.at(x, y, c) * (0.5f + 0.01f * float(x + y));
        noisy.at(x, y, c) = clean.at(x, y, c) * (1.0f + 0.01f * noise(rng));
      }
  const Image blurred = box_blur(noisy, 2);
  Image on_colour = blurred, on_light = blurred;
  const StepBackStats sc = step_back(noisy, Roi::all(w, h), 4, 2, on_colour);
  const StepBackStats sl = step_back(noisy, Roi::all(w, h), 4, 2, on_light, nullptr, 1.0, &albedo);
  EXPECT_LT(relmse(on_light, clean), 2.0 * relmse(noisy, clean));
  EXPECT_LT(relmse(on_light, clean), 0.1 * relmse(on_colour, clean));
  EXPECT_LT(sl.mean_weight, 0.1);
  EXPECT_GT(sc.mean_weight, 0.3);
}

// An emitter's Denoising Albedo is its emission: the studio still's screen reads the same wave
// picture (0.4 to 2.7) in both passes, and the picture is no noise. Capped at 1 (the filters'
// demodulation rule) the picture stayed in the "illumination" the noise is estimated on, and the
// step back kept pwaf's blur of it: 0.028 on the screen against the input's 0.013. Oracle: the
// 2048-spp reference, over the screen (x 160-223, y 32-63).
TEST(StepBack, AnEmittersPictureIsNotReadAsNoise) {
  const std::string dir = std::string(MCRECON_SOURCE_DIR) + "/samples/data/studio/";
  const Frame f = read_frame(dir + "studio_64spp.exr");
  const Image ref = read_frame(dir + "studio_ref.exr").image(Role::Colour);
  auto pwaf = make_filter("pwaf");
  pwaf->commit();
  const Image out = pwaf->execute(f);
  auto screen = [](const Image& a) {
    Image o(64, 32, 3);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 64; ++x)
        for (int c = 0; c < 3; ++c) o.at(x, y, c) = a.at(160 + x, 32 + y, c);
    return o;
  };
  const double in_err = relmse(screen(f.image(Role::Colour)), screen(ref));
  EXPECT_LT(relmse(screen(out), screen(ref)), 0.5 * in_err);
}

// A variance pass is each pixel's own, exact in expectation: it is not scaled.
TEST(StepBack, AVariancePassIsNotScaled) {
  Image clean;
  const Image noisy = scene(64, 48, 0.2, 8, &clean);
  Image var(64, 48, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) var.at(x, y, c) = float(std::pow(0.2 * clean.at(x, y, c), 2));
  const Image blurred = box_blur(noisy, 3);
  Image a = blurred, b = blurred;
  step_back(noisy, Roi::all(64, 48), 4, 2, a, &var, 1.0);
  step_back(noisy, Roi::all(64, 48), 4, 2, b, &var, 2.0);
  EXPECT_EQ(a.storage(), b.storage());
}

// A variance pass from two halves is one draw per pixel, heavy-tailed where a few samples make
// each half: with the truth as the result, the 9x9 ratio alone blends some of the input's noise
// back wherever a window's draws run low; the 17x17 window keeps the result. A blur across every
// block edge is still stepped back from (no worse than the input or itself). Oracle: the clean
// image. Noise: each half the mean of 4 samples, each the level / p with probability p = 0.5
// (Monte Carlo's skew), else 0.
TEST(StepBack, AVariancePassFromHalvesKeepsASoundResultAndStillStepsBackFromABlur) {
  const int w = 120, h = 96;
  Image clean;
  scene(w, h, 0.0, 9, &clean);
  std::mt19937 rng(4);
  std::bernoulli_distribution hit(0.5);
  Image noisy(w, h, 3), var(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        double half[2];
        for (double& m : half) {
          m = 0;
          for (int k = 0; k < 4; ++k) m += hit(rng) ? clean.at(x, y, c) / 0.5 / 4 : 0.0;
        }
        noisy.at(x, y, c) = float(0.5 * (half[0] + half[1]));
        var.at(x, y, c) = float((half[0] - half[1]) * (half[0] - half[1]) / 4);
      }
  Image kept = clean;
  step_back(noisy, Roi::all(w, h), 4, 2, kept, &var);
  // 0.0026 of the input's error with the wide window, 0.008 with the 9x9 one alone.
  EXPECT_LT(relmse(kept, clean), 0.005 * relmse(noisy, clean));
  const Image blurred = box_blur(noisy, 4);
  Image out = blurred;
  step_back(noisy, Roi::all(w, h), 4, 2, out, &var);
  EXPECT_LT(relmse(out, clean), relmse(noisy, clean));
  EXPECT_LT(relmse(out, clean), relmse(blurred, clean));
}

TEST(StepBack, AFireflyGoesAndItsLightStaysWhereItWas) {
  Image clean;
  Image noisy = scene(48, 48, 0.05, 4, &clean);
  for (int c = 0; c < 3; ++c) noisy.at(30, 30, c) = 1000.0f;
  const Image blurred = box_blur(noisy, 2);
  Image out = blurred;
  const StepBackStats st = step_back(noisy, Roi::all(48, 48), 4, 1, out);
  EXPECT_EQ(st.fireflies, 1u);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(out.at(30, 30, c), blurred.at(30, 30, c));  // the filter's value
  for (int y = 28; y <= 32; ++y)
    for (int x = 28; x <= 32; ++x)
      if (x != 30 || y != 30)
        for (int c = 0; c < 3; ++c) EXPECT_LT(out.at(x, y, c), clean.at(x, y, c) * 1.5f + 0.01f) << x << "," << y;
}

// A one-pixel bright line through a dark noisy wall: a blur pulls its light into the dark
// pixels beside it, whose 3x3 range holds the line (so the range clamp cannot catch it)
// and whose window is mostly fine. The per-pixel limit against the 3x3 median does.
TEST(StepBack, LightIsNotPulledFromABrightLineIntoItsDarkNeighbours) {
  const int w = 64, h = 48;
  std::mt19937 rng(8);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  Image clean(w, h, 3), noisy(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = x == 32 ? 5.0f : 0.1f;
        clean.at(x, y, c) = v;
        noisy.at(x, y, c) = v * (1.0f + 0.3f * noise(rng));
      }
  const Image blurred = box_blur(noisy, 2);
  Image out = blurred;
  step_back(noisy, Roi::all(w, h), 4, 1, out);
  double in_err = 0, out_err = 0;
  for (int y = 0; y < h; ++y)
    for (int x : {31, 33})
      for (int c = 0; c < 3; ++c) {
        in_err += std::pow(noisy.at(x, y, c) - clean.at(x, y, c), 2);
        out_err += std::pow(out.at(x, y, c) - clean.at(x, y, c), 2);
      }
  EXPECT_LT(out_err, 2.0 * in_err);
}

TEST(StepBack, NonFiniteInputKeepsTheResultAndOnlyTheRegionChanges) {
  Image noisy = scene(40, 30, 0.2, 5);
  noisy.at(12, 12, 0) = std::numeric_limits<float>::quiet_NaN();
  noisy.at(13, 12, 2) = -std::numeric_limits<float>::infinity();
  Image blurred = box_blur(noisy, 2);
  for (int c = 0; c < 3; ++c) blurred.at(12, 12, c) = blurred.at(13, 12, c) = 0.5f;  // as finish() leaves them
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x)
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(blurred.at(x, y, c))) blurred.at(x, y, c) = 0.5f;
  Image out = blurred;
  const Roi roi{5, 5, 30, 25};
  step_back(noisy, roi, 4, 2, out);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x)
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(out.at(x, y, c)));
        if (!roi.contains(x, y) || (y == 12 && (x == 12 || x == 13)))
          EXPECT_EQ(out.at(x, y, c), blurred.at(x, y, c)) << x << "," << y;
      }
}

// Through a filter: on by default, noted, and off gives the filter's own result.
TEST(StepBack, EveryImageFilterTakesItByDefault) {
  const Frame f = testutil::colour_frame(scene(40, 30, 0.2, 6));
  for (const std::string& name : image_filter_names()) {
    auto on = make_filter(name);
    if (on->info().temporal) {  // on by default, for a frame without history only (BmfrHighlights tests it)
      EXPECT_TRUE(on->params().get_bool("step_back")) << name;
      continue;
    }
    SCOPED_TRACE(name);
    ASSERT_TRUE(on->params().get_bool("step_back"));
    if (!on->missing_passes(f).empty()) continue;
    // At the frame's own exposure: the step back below is applied to it as it is.
    on->set("exposure", std::string("off"));
    on->commit();
    const Image a = on->execute(f);
    bool noted = false;
    for (const std::string& n : on->notes()) noted = noted || n.rfind("step_back:", 0) == 0;
    EXPECT_TRUE(noted);
    auto off = make_filter(name);
    off->set("step_back", false);
    off->set("exposure", std::string("off"));
    off->commit();
    const Image b = off->execute(f);
    Image expect = b;
    step_back(f.image(Role::Colour), Roi::all(40, 30), 4, 0, expect, nullptr, step_back_noise_for(on->params(), f));
    EXPECT_EQ(a.storage(), expect.storage());
  }
}

}  // namespace
}  // namespace mcr
