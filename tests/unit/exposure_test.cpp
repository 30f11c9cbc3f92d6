// The exposure step (prepare/exposure.h): a render far from display exposure is filtered
// scaled into [0.18, 1] by a power of two and scaled back. Oracles: the level's closed form;
// equivariance of the filtering (two renders a power of two apart, both outside the band, give
// results exactly that power of two apart with the step back off: the scaled frames are the
// same bits); and the step back weighing as relMSE does on the render itself (prepare/step_back.h
// called by hand with relMSE's term at the render's scale).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "pipeline/auto_filter.h"
#include "prepare/exposure.h"
#include "prepare/step_back.h"

namespace mcr {
namespace {

using testutil::add_pass;
using testutil::random_image;

// A render with every pass the image filters read: colour at mean luminance about `level`,
// a variance pass that matches its noise (pwaf and auto read it).
Frame render_at(double level, unsigned seed) {
  Frame f = testutil::full_frame(48, 32, seed);
  Image& c = f.passes.front().image;
  const Image noise = random_image(48, 32, 3, seed + 9, -0.3f, 0.3f);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 48; ++x)
      for (int ch = 0; ch < 3; ++ch)  // a lit half and a shadow, with noise
        c.at(x, y, ch) = float(level * 2.0 * (x < 24 ? 1.6 : 0.4) * (1.0 + noise.at(x, y, ch)));
  add_pass(f, Role::Variance, Image(48, 32, 3, float(level * level * 0.1)));
  return f;
}

Frame scaled(Frame f, float k) {
  for (Pass& p : f.passes) {
    if (p.role == Role::Colour)
      for (float& v : p.image.storage()) v *= k;
    if (p.role == Role::Variance)
      for (float& v : p.image.storage()) v *= k * k;
  }
  return f;
}

std::unique_ptr<Filter> make(const std::string& name) {
  if (name == "auto") return std::make_unique<AutoFilter>();
  return make_filter(name);
}

// Values of b that are not exactly k times a.
long not_scaled(const Image& a, const Image& b, float k) {
  long n = 0;
  for (std::size_t i = 0; i < a.storage().size(); ++i) {
    const float want = a.storage()[i] * k, got = b.storage()[i];
    n += std::memcmp(&want, &got, sizeof got) != 0;
  }
  return n;
}

TEST(Exposure, TheLevelIsTheMeanAbsoluteLuminanceOfTheFinitePixels) {
  Image im(4, 2, 3, 0.0f);
  const float px[4][3] = {{1, 0, 0}, {0, -2, 0}, {0, 0, 4}, {std::numeric_limits<float>::quiet_NaN(), 1, 1}};
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) im.at(i, 0, c) = px[i][c];
  ExposureLevel e;
  e.add(im, Roi::all(4, 2), 2);
  // Row 0: 0.2126 + 2 x 0.7152 + 4 x 0.0722 over three finite pixels; row 1: four zeros.
  EXPECT_DOUBLE_EQ(e.count, 7.0);
  EXPECT_NEAR(e.level(), (0.2126 + 2 * 0.7152 + 4 * 0.0722) / 7.0, 1e-12);
  EXPECT_EQ(e.least, 1.0);
  EXPECT_EQ(e.most, 4.0);
  // In bands of rows, in frame order: the same sums.
  ExposureLevel a;
  a.add(im, Roi{0, 0, 4, 1}, 1);
  a.add(im, Roi{0, 1, 4, 2}, 1);
  EXPECT_EQ(a.sum, e.sum);
  EXPECT_EQ(a.count, e.count);
}

TEST(Exposure, TheScaleIsTheLeastPowerOfTwoIntoTheBand) {
  auto scale = [](double level, double least = 1e-3, double most = 10.0) {
    ExposureLevel e;
    e.sum = level;
    e.count = 1;
    e.least = least;
    e.most = most;
    return exposure_scale(e);
  };
  EXPECT_EQ(scale(0.3), 1.0);
  EXPECT_EQ(scale(kExposureLow), 1.0);
  EXPECT_EQ(scale(kExposureHigh), 1.0);
  EXPECT_EQ(scale(0.1), 2.0);      // 0.2
  EXPECT_EQ(scale(0.01), 32.0);    // 0.32: 16 gives 0.16
  EXPECT_EQ(scale(3.0), 0.25);     // 0.75: 0.5 gives 1.5
  EXPECT_EQ(scale(0.0), 1.0);
  EXPECT_EQ(scale(std::numeric_limits<double>::infinity()), 1.0);
  // No value is pushed beyond 2^120: a frame that holds 2^118 is scaled up by 4 at most,
  // one that holds 2^-118 down by 4 at most.
  EXPECT_EQ(scale(1e-6, 1e-6, std::ldexp(1.0, 118)), 4.0);
  EXPECT_EQ(scale(100.0, std::ldexp(1.0, -118), 100.0), 0.25);
  EXPECT_EQ(scale(1e-6, 1e-6, std::ldexp(1.0, 125)), 1.0);
}

std::unique_ptr<Filter> without_step_back(const std::string& name) {
  auto f = make(name);
  if (f->params().has("step_back")) f->set("step_back", false);
  return f;
}

// Every image filter: a render and the same 4x brighter, both below the band, filtered 4x
// apart bit for bit (the step back, which weighs by relMSE at each render's own exposure, off);
// with exposure=off they are not (the check has teeth).
TEST(Exposure, EveryImageFilterFiltersTheSameAtAnyExposureBelowTheBand) {
  const Frame dim = render_at(0.01, 3), brighter = scaled(dim, 4.0f);
  bool off_differs = false;
  for (const std::string& name : image_filter_names()) {
    SCOPED_TRACE(name);
    auto a = without_step_back(name), b = without_step_back(name);
    a->commit();
    b->commit();
    const Image ra = a->execute(dim), rb = b->execute(brighter);
    EXPECT_EQ(not_scaled(ra, rb, 4.0f), 0);
    bool noted = false;  // mean luminance 0.02: filtered at 16x
    for (const std::string& n : a->notes()) noted = noted || n.rfind("exposure: filtered at 16x", 0) == 0;
    EXPECT_TRUE(noted);
    if (a->info().temporal) {  // the second frame at the first one's scale (its history's)
      const Frame next = scaled(dim, 1.5f);
      EXPECT_EQ(not_scaled(a->execute(next), b->execute(scaled(next, 4.0f)), 4.0f), 0);
    }
    auto c = without_step_back(name), d = without_step_back(name);
    c->set("exposure", std::string("off"));
    d->set("exposure", std::string("off"));
    c->commit();
    d->commit();
    off_differs = off_differs || not_scaled(c->execute(dim), d->execute(brighter), 4.0f) > 0;
  }
  EXPECT_TRUE(off_differs);
}

// A temporal filter keeps its first frame's scale: its history is at that scale. The second
// frame here is 1.4x brighter (its own scale would be 8, not 16).
TEST(Exposure, ATemporalFilterKeepsTheFirstFramesScale) {
  const Frame first = render_at(0.01, 7), second = scaled(first, 1.4f);
  auto a = without_step_back("bmfr"), b = without_step_back("bmfr");
  b->set("exposure", std::string("off"));
  a->commit();
  b->commit();
  EXPECT_EQ(not_scaled(a->execute(first), b->execute(scaled(first, 16.0f)), 16.0f), 0);
  EXPECT_EQ(not_scaled(a->execute(second), b->execute(scaled(second, 16.0f)), 16.0f), 0);
  // reset() drops it with the history: the second frame alone at its own scale, 8.
  a->reset();
  b->reset();
  EXPECT_EQ(not_scaled(a->execute(second), b->execute(scaled(second, 8.0f)), 8.0f), 0);
}

// Above the band too, and a render inside it is filtered as it is.
TEST(Exposure, AboveTheBandScaledDownInsideItAsItIs) {
  const Frame bright = render_at(5.0, 4), brighter = scaled(bright, 8.0f), inside = render_at(0.4, 4);
  for (const char* name : {"pwaf", "guided", "auto"}) {
    SCOPED_TRACE(name);
    auto c = make(name), d = make(name);
    d->set("exposure", std::string("off"));
    c->commit();
    d->commit();
    EXPECT_EQ(not_scaled(c->execute(inside), d->execute(inside), 1.0f), 0);
    if (std::string(name) == "auto") continue;  // its scores are relMSE at each render's exposure
    auto a = without_step_back(name), b = without_step_back(name);
    a->commit();
    b->commit();
    EXPECT_EQ(not_scaled(a->execute(bright), b->execute(brighter), 8.0f), 0);
  }
}

// A setting in the render's colour units follows it: an absolute colour sigma 4x larger on
// the 4x brighter render gives the 4x result.
TEST(Exposure, AnAbsoluteColourSigmaIsInTheRendersUnits) {
  const Frame dim = render_at(0.01, 5), brighter = scaled(dim, 4.0f);
  for (const char* name : {"bilateral", "atrous"}) {
    SCOPED_TRACE(name);
    auto a = without_step_back(name), b = without_step_back(name);
    for (auto* f : {a.get(), b.get()}) f->set("colour_weight", std::string("absolute"));
    a->set("colour_sigma", 0.005);
    b->set("colour_sigma", 0.02);
    a->commit();
    b->commit();
    EXPECT_EQ(not_scaled(a->execute(dim), b->execute(brighter), 4.0f), 0);
  }
  // clamp likewise.
  auto a = without_step_back("box"), b = without_step_back("box");
  a->set("clamp", 0.01);
  b->set("clamp", 0.04);
  a->commit();
  b->commit();
  EXPECT_EQ(not_scaled(a->execute(dim), b->execute(brighter), 4.0f), 0);
}

// The step back on a scaled render weighs errors as relMSE does on the render itself: box on a
// dim render (filtered at 16x) is the box result of the 16x frame, stepped back with relMSE's
// term 0.01 x 16^2, scaled back.
TEST(Exposure, TheStepBackWeighsAsRelMseOnTheRenderItself) {
  const Frame dim = render_at(0.01, 8), lifted = scaled(dim, 16.0f);
  auto a = make("box");
  a->commit();
  const Image got = a->execute(dim);
  auto b = without_step_back("box");
  b->set("exposure", std::string("off"));
  b->commit();
  const Image f = b->execute(lifted);
  const Image& colour = lifted.image(Role::Colour);
  const Image& variance = lifted.image(Role::Variance);
  Image want = f, plain = f;
  step_back(colour, Roi::all(48, 32), 4, 2, want, &variance, 1.0, nullptr, 0.01 * 16 * 16);
  step_back(colour, Roi::all(48, 32), 4, 2, plain, &variance, 1.0, nullptr, 0.01);
  EXPECT_EQ(not_scaled(got, want, 16.0f), 0);
  EXPECT_GT(not_scaled(got, plain, 16.0f), 0);  // the term matters here
}

// Non-finite input stays the filter's business: nothing non-finite leaves, at any exposure.
TEST(Exposure, NonFiniteInputOfADimRender) {
  Frame f = render_at(0.002, 6);
  Image& c = f.passes.front().image;
  c.at(5, 5, 0) = std::numeric_limits<float>::quiet_NaN();
  c.at(9, 7, 1) = std::numeric_limits<float>::infinity();
  c.at(30, 20, 2) = 1.0e6f;  // a firefly, still scaled into the band (under 2^120)
  for (const std::string& name : image_filter_names()) {
    SCOPED_TRACE(name);
    auto filt = make(name);
    filt->commit();
    const Image out = filt->execute(f);
    for (float v : out.storage()) ASSERT_TRUE(std::isfinite(v));
    EXPECT_EQ(filt->nonfinite_repaired(), 0u);
  }
}

}  // namespace
}  // namespace mcr
