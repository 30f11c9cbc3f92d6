// Albedo prefiltering (common parameter albedo_prefilter): texture edges of a clean
// albedo survive exactly, multiplicative noise on a flat albedo shrinks, non-finite
// albedo keeps the demodulation policy, and every filter stays finite with it.
#include "prepare/albedo_prefilter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "feature_filter_testutil.h"
#include "filters/image/box.h"
#include "filters/registry.h"

namespace mcr {
namespace {

using namespace testutil;

// A checker of two albedos on a plane (normal and position smooth).
Frame checker_frame(int w, int h, float lo, float hi) {
  Frame f = colour_frame(Image(w, h, 3, 1.0f));
  Image alb(w, h, 3), nor(w, h, 3), pos(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) alb.at(x, y, c) = ((x / 4 + y / 4) % 2) ? hi : lo;
      nor.at(x, y, 0) = 0, nor.at(x, y, 1) = 0, nor.at(x, y, 2) = 1;
      pos.at(x, y, 0) = 0.01f * x, pos.at(x, y, 1) = 0.01f * y, pos.at(x, y, 2) = 0;
    }
  add_pass(f, Role::Albedo, alb);
  add_pass(f, Role::Normal, nor);
  add_pass(f, Role::Position, pos);
  return f;
}

TEST(AlbedoPrefilter, CleanTextureEdgesAreKept) {
  const Frame f = checker_frame(24, 16, 0.1f, 0.8f);
  const Pass& a = *f.find(Role::Albedo);
  const Image out = prefilter_albedo(f, a, AlbedoPrefilter{}, Roi::all(f.width, f.height), 0);
  for (std::size_t i = 0; i < out.storage().size(); ++i)
    ASSERT_NEAR(out.storage()[i], a.image.storage()[i], 1e-5 * a.image.storage()[i]) << "value " << i;
}

TEST(AlbedoPrefilter, MultiplicativeNoiseOnAFlatAlbedoShrinks) {
  Frame f = checker_frame(32, 32, 0.5f, 0.5f);
  Image& a = pass_image(f, Role::Albedo);
  std::mt19937 rng(4);
  std::normal_distribution<float> n(0.0f, 0.03f);
  for (float& v : a.storage()) v *= std::exp(n(rng));
  const Image out = prefilter_albedo(f, *f.find(Role::Albedo), AlbedoPrefilter{}, Roi::all(f.width, f.height), 0);
  auto log_var = [](const Image& im) {
    double s = 0, s2 = 0;
    for (float v : im.storage()) s += std::log(v), s2 += std::log(v) * std::log(v);
    const double m = s / double(im.storage().size());
    return s2 / double(im.storage().size()) - m * m;
  };
  EXPECT_LT(log_var(out), log_var(a) / 3) << "a 1-px first-order fit averages about a dozen pixels";
}

TEST(AlbedoPrefilter, NonFiniteAlbedoKeepsItsValue) {
  Frame f = checker_frame(12, 10, 0.2f, 0.6f);
  Image& a = pass_image(f, Role::Albedo);
  a.at(3, 3, 1) = kNaN;
  a.at(7, 5, 0) = kInf;
  const Image out = prefilter_albedo(f, *f.find(Role::Albedo), AlbedoPrefilter{}, Roi::all(f.width, f.height), 0);
  EXPECT_TRUE(std::isnan(out.at(3, 3, 1)));
  EXPECT_EQ(out.at(7, 5, 0), kInf);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 12; ++x)
      for (int c = 0; c < 3; ++c)
        if (std::isfinite(a.at(x, y, c))) ASSERT_TRUE(std::isfinite(out.at(x, y, c))) << x << "," << y;
}

// Through the base class: with demodulation, radius 0 and a constant illumination
// the output is the prefiltered albedo times that illumination.
TEST(AlbedoPrefilter, DemodulationUsesTheSmoothedAlbedo) {
  Frame f = checker_frame(20, 20, 0.5f, 0.5f);
  Image& a = pass_image(f, Role::Albedo);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.9f, 1.1f);
  for (float& v : a.storage()) v *= u(rng);
  Image& c = pass_image(f, Role::Colour);
  for (std::size_t i = 0; i < c.storage().size(); ++i) c.storage()[i] = 2.0f * a.storage()[i];
  const Image smooth = prefilter_albedo(f, *f.find(Role::Albedo), AlbedoPrefilter{}, Roi::all(f.width, f.height), 0);
  BoxFilter box;
  box.set("radius", std::int64_t(20));
  box.set("demodulate", true);
  box.set("albedo_prefilter", 0.2);
  box.commit();
  const Image out = box.execute(f);
  // The window holds the whole image: out = (mean of c / a~) * a~ at each pixel, so
  // out / a~ is one value per channel (with the raw albedo it would vary by 10%), that mean.
  for (int ch = 0; ch < 3; ++ch) {
    double m = 0;
    for (std::size_t i = std::size_t(ch); i < c.storage().size(); i += 3) m += c.storage()[i] / smooth.storage()[i];
    m /= double(c.storage().size() / 3);
    const double r0 = out.storage()[std::size_t(ch)] / smooth.storage()[std::size_t(ch)];
    EXPECT_NEAR(r0, m, 2e-3 * m) << "channel " << ch;
    for (std::size_t i = std::size_t(ch); i < out.storage().size(); i += 3)
      ASSERT_NEAR(out.storage()[i] / smooth.storage()[i], r0, 1e-5 * r0) << "value " << i;
  }
}

TEST(AlbedoPrefilter, EveryFilterStaysFiniteWithIt) {
  for (const std::string& name : image_filter_names()) {
    Frame f = full_frame(20, 14, 5);
    pass_image(f, Role::Albedo).at(4, 4, 0) = kNaN;
    pass_image(f, Role::Albedo).at(9, 2, 2) = 0.0f;
    pass_image(f, Role::Position).at(6, 6, 1) = kInf;
    auto filter = make_filter(name);
    filter->set("albedo_prefilter", 0.2);
    filter->set(filter->params().has("demodulate") ? "demodulate" : "albedo_demodulation", true);
    filter->commit();
    const Image out = filter->execute(f);
    for (float v : out.storage()) ASSERT_TRUE(std::isfinite(v)) << name;
    EXPECT_EQ(filter->nonfinite_repaired(), 0u) << name;
  }
}

// Holes filled by pull-push first, then the albedo smoothed: the filled frame is the one
// prefiltered (the base class reuses its copy), and the result equals prefiltering a
// frame whose passes were filled beforehand.
TEST(AlbedoPrefilter, WorksOnTheHoleFilledFrame) {
  Frame f = full_frame(16, 12, 3);
  Image spp(16, 12, 1, 4.0f);
  for (int i = 0; i < 12; ++i) spp.at((i * 5) % 16, (i * 7) % 12, 0) = 0.0f;
  add_pass(f, Role::SampleCount, spp);
  auto run_box = [](const Frame& frame, const std::string& holes) {
    BoxFilter box;
    box.set("radius", std::int64_t(1));
    box.set("demodulate", true);
    box.set("albedo_prefilter", 0.2);
    box.set("holes", holes);
    box.commit();
    return box.execute(frame);
  };
  const Image direct = run_box(f, "auto");
  for (float v : direct.storage()) ASSERT_TRUE(std::isfinite(v));
  BoxFilter fill;  // radius 0: the hole-filled colour, pass by pass through the same fill
  fill.set("radius", std::int64_t(0));
  fill.commit();
  Frame pre = f;
  for (Pass& p : pre.passes) {
    if (p.role == Role::SampleCount) continue;
    Frame one = colour_frame(Image(16, 12, 3));
    Image wide(16, 12, 3);
    for (int y = 0; y < 12; ++y)
      for (int x = 0; x < 16; ++x)
        for (int c = 0; c < 3; ++c) wide.at(x, y, c) = p.image.at(x, y, std::min(c, p.image.channels() - 1));
    pass_image(one, Role::Colour) = wide;
    add_pass(one, Role::SampleCount, spp);
    const Image filled = fill.execute(one);
    for (int y = 0; y < 12; ++y)
      for (int x = 0; x < 16; ++x)
        for (int c = 0; c < p.image.channels(); ++c) p.image.at(x, y, c) = filled.at(x, y, c);
  }
  for (Pass& p : pre.passes)
    if (p.role == Role::SampleCount) p.image = Image(16, 12, 1, 4.0f);
  const Image staged = run_box(pre, "auto");
  for (std::size_t i = 0; i < direct.storage().size(); ++i)
    ASSERT_NEAR(direct.storage()[i], staged.storage()[i], 1e-5 * std::max(1.0f, std::fabs(staged.storage()[i])))
        << "value " << i;
}

}  // namespace
}  // namespace mcr
