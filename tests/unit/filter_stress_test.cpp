// Numerical stress for EVERY registered filter (new filters are covered by
// registering them): outputs stay finite, the filter itself produces no
// non-finite value (the base class safety net stays idle), and constant input
// stays constant.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "expect_error.h"
#include "filters/registry.h"

namespace mcr {
namespace {

Pass make_pass(Role role, int w, int h, int channels, float fill) {
  Pass p;
  p.role = role;
  p.name = role_name(role);
  p.source = "memory";
  p.space = (role == Role::Normal || role == Role::Position) ? Space::World : Space::None;
  p.image = Image(w, h, channels, fill);
  return p;
}

// A frame with every role a filter might use, random but plausible content.
Frame full_frame(int w, int h, unsigned seed) {
  Frame f;
  f.width = w;
  f.height = h;
  f.path = "stress";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (Role r : {Role::Colour, Role::Albedo, Role::Normal, Role::Position, Role::Depth, Role::Motion, Role::Variance,
                 Role::SecondPosition, Role::SecondNormal}) {
    Pass p = make_pass(r, w, h, role_channels(r), 0.0f);
    for (float& v : p.image.storage()) v = u(rng);
    f.passes.push_back(std::move(p));
  }
  f.passes.push_back(make_pass(Role::SampleCount, w, h, 1, 16.0f));
  f.passes.push_back(make_pass(Role::Alpha, w, h, 1, 1.0f));
  return f;
}

Pass& pass_of(Frame& f, Role r) {
  for (Pass& p : f.passes)
    if (p.role == r) return p;
  throw std::runtime_error("no pass");
}

void expect_clean(const std::string& name, Filter& filter, const Frame& frame, const std::string& what) {
  Image out;
  ASSERT_NO_THROW(out = filter.execute(frame)) << name << ": " << what;
  ASSERT_EQ(out.width(), frame.width);
  ASSERT_EQ(out.height(), frame.height);
  for (float v : out.storage()) ASSERT_TRUE(std::isfinite(v)) << name << ": " << what;
  EXPECT_EQ(filter.nonfinite_repaired(), 0u) << name << " produced non-finite values itself: " << what;
}

std::unique_ptr<Filter> committed(const std::string& name) {
  auto f = make_filter(name);
  f->commit();
  return f;
}

TEST(FilterStress, EveryFilterKeepsAConstantImageConstant) {
  for (const std::string& name : image_filter_names()) {
    if (filter_info(name).temporal) continue;  // history makes the first frames special
    Frame f = full_frame(23, 17, 1);
    for (float& v : pass_of(f, Role::Colour).image.storage()) v = 0.375f;
    // A constant albedo too: guided and pwaf demodulate by default, and a constant colour over
    // a varied albedo is a varied illumination, which they rightly smooth.
    for (float& v : pass_of(f, Role::Albedo).image.storage()) v = 0.6f;
    auto filter = committed(name);
    const Image out = filter->execute(f);
    for (float v : out.storage()) EXPECT_NEAR(v, 0.375f, 1e-4f) << name;
  }
}

// A constant at the ends of the float range stays that constant (relative 1e-3), with the
// default settings and with demodulation by a dark albedo (constant: a varied one would make
// the illumination vary; colour / albedo would pass FLT_MAX, and prepare/demodulation.h's
// divisor rule keeps it finite). Negative radiance
// is legal input. Temporal filters run three frames of one static shot.
TEST(FilterStress, ExtremeConstantsStayConstant) {
  const float big = std::numeric_limits<float>::max();
  for (const std::string& name : image_filter_names())
    for (float value : {big, -big, 1e30f, -1e30f, 1e-30f})
      for (bool demodulate : {false, true}) {
        auto filter = make_filter(name);
        const char* key = filter->params().has("demodulate") ? "demodulate" : "albedo_demodulation";
        if (filter->params().has(key)) {
          filter->set(key, demodulate);
        } else if (demodulate) {
          continue;  // no demodulation setting: the default run covers it
        }
        filter->commit();
        const std::string what = name + " on " + std::to_string(value) + (demodulate ? " demodulated" : "");
        for (int frame = 0; frame < 3; ++frame) {
          Frame f = full_frame(19, 14, 8);
          for (float& v : pass_of(f, Role::Colour).image.storage()) v = value;
          for (float& v : pass_of(f, Role::Motion).image.storage()) v = 0.0f;  // static: the history lines up
          for (float& v : pass_of(f, Role::Albedo).image.storage()) v = 0.3f;  // colour / albedo passes FLT_MAX
          const Image out = filter->execute(f);
          ASSERT_EQ(filter->nonfinite_repaired(), 0u) << what << ", frame " << frame;
          for (float v : out.storage()) {
            ASSERT_TRUE(std::isfinite(v)) << what;
            ASSERT_LE(std::fabs(double(v) - double(value)), 1e-3 * std::fabs(double(value)))
                << what << ", frame " << frame << ": " << v;
          }
        }
      }
}

TEST(FilterStress, DegenerateSizes) {
  for (const std::string& name : image_filter_names())
    for (auto [w, h] : {std::pair{1, 1}, {1, 9}, {9, 1}, {2, 2}, {3, 40}}) {
      auto filter = committed(name);
      expect_clean(name, *filter, full_frame(w, h, 2), std::to_string(w) + "x" + std::to_string(h));
    }
}

TEST(FilterStress, ExtremeMagnitudes) {
  for (const std::string& name : image_filter_names())
    for (float scale : {1e-30f, 1e30f, 3e38f}) {
      Frame f = full_frame(16, 12, 3);
      for (float& v : pass_of(f, Role::Colour).image.storage()) v *= scale;
      auto filter = committed(name);
      expect_clean(name, *filter, f, "colour scaled by " + std::to_string(scale));
      // Features at extreme magnitudes too.
      Frame g = full_frame(16, 12, 4);
      for (Role r : {Role::Position, Role::Depth}) for (float& v : pass_of(g, r).image.storage()) v *= scale;
      auto filter2 = committed(name);
      expect_clean(name, *filter2, g, "position/depth scaled by " + std::to_string(scale));
    }
}

TEST(FilterStress, NonFiniteInColourAndEveryFeature) {
  const float bad[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                       -std::numeric_limits<float>::infinity()};
  for (const std::string& name : image_filter_names())
    for (Role r : {Role::Colour, Role::Albedo, Role::Normal, Role::Position, Role::Depth, Role::Motion, Role::Variance,
                   Role::SecondPosition, Role::SecondNormal, Role::SampleCount})
      for (float b : bad) {
        Frame f = full_frame(20, 14, 5);
        Image& img = pass_of(f, r).image;
        // A scattered handful of bad pixels plus one whole bad row.
        for (int i = 0; i < 9; ++i) img.at((i * 7) % 20, (i * 5) % 14, 0) = b;
        for (int x = 0; x < 20; ++x) img.at(x, 6, img.channels() - 1) = b;
        auto filter = committed(name);
        expect_clean(name, *filter, f, std::string(role_name(r)) + " with " + std::to_string(b));
      }
}

TEST(FilterStress, ZeroAlbedoWithDemodulation) {
  for (const std::string& name : image_filter_names()) {
    Frame f = full_frame(18, 13, 6);
    for (float& v : pass_of(f, Role::Albedo).image.storage()) v = 0.0f;
    auto filter = make_filter(name);
    filter->set(filter->params().has("demodulate") ? "demodulate" : "albedo_demodulation", true);
    filter->commit();
    expect_clean(name, *filter, f, "zero albedo, demodulate");
  }
}

// A region not entirely inside the frame (or empty) is refused, naming the region and the
// image's extent: clipping it silently hid a typo (issue 13). The whole frame given as a
// region is the whole frame.
TEST(FilterStress, RegionNotInsideTheFrameIsRefused) {
  const Frame f = full_frame(18, 13, 7);
  for (const std::string& name : image_filter_names()) {
    SCOPED_TRACE(name);
    auto filter = make_filter(name);
    filter->commit();
    for (const Roi& r : {Roi{40, 40, 50, 50}, Roi{10, 5, 19, 8}, Roi{0, 0, 18, 14}, Roi{-1, 0, 5, 5},
                         Roi{5, 5, 5, 9}, Roi{6, 4, 2, 9}}) {
      ExecOptions o;
      o.roi = r;
      const std::string text = std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) +
                               "," + std::to_string(r.y1);
      const std::string msg = testutil::expect_error(Errc::InvalidArgument, [&] { filter->execute(f, o); });
      EXPECT_NE(msg.find("region " + text), std::string::npos) << msg;
      if (!r.empty()) EXPECT_NE(msg.find("outside the 18x13 image (x in [0, 18), y in [0, 13))"), std::string::npos) << msg;
      else EXPECT_NE(msg.find("empty"), std::string::npos) << msg;
    }
    ExecOptions whole;
    whole.roi = Roi{0, 0, 18, 13};
    const Image a = filter->execute(f, whole);
    auto fresh = make_filter(name);
    fresh->commit();
    const Image b = fresh->execute(f);
    for (int y = 0; y < f.height; ++y)
      for (int x = 0; x < f.width; ++x)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(a.at(x, y, c), b.at(x, y, c)) << x << "," << y;
  }
}

TEST(FilterStress, AllEqualFeaturesAndFireflies) {
  for (const std::string& name : image_filter_names()) {
    Frame f = full_frame(24, 24, 7);
    for (Role r : {Role::Albedo, Role::Normal, Role::Position, Role::Depth, Role::SecondPosition, Role::SecondNormal})
      for (float& v : pass_of(f, r).image.storage()) v = 0.5f;
    pass_of(f, Role::Colour).image.at(12, 12, 0) = 1e6f;  // a firefly
    auto filter = committed(name);
    expect_clean(name, *filter, f, "equal features + firefly");
  }
}

}  // namespace
}  // namespace mcr
