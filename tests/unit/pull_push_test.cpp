#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "prepare/pull_push.h"
#include "filters/registry.h"
#include "sparse/expanded_grid.h"

namespace mcr {
namespace {

Image ramp(int w, int h) {
  Image img(w, h, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      img.at(x, y, 0) = 0.5f + 0.01f * x;
      img.at(x, y, 1) = -2.0f + 0.02f * y;
    }
  return img;
}

TEST(PullPush, ConstantImageIsFilledExactly) {
  Image img(37, 23, 3, 0.7f);
  std::vector<float> w(img.pixel_count(), 0.0f);
  std::mt19937 rng(1);
  for (auto& v : w) v = (rng() % 5 == 0) ? 1.0f : 0.0f;
  for (std::size_t i = 0; i < w.size(); ++i)
    if (w[i] == 0) std::fill(img.data() + i * 3, img.data() + i * 3 + 3, 123.0f);  // garbage in holes
  pull_push_fill(img, w);
  for (float v : img.storage()) EXPECT_NEAR(v, 0.7f, 1e-6f);
}

TEST(PullPush, SampledPixelsKeepTheirValues) {
  Image img = ramp(40, 30);
  const Image orig = img;
  std::vector<float> w(img.pixel_count(), 0.0f);
  for (std::size_t i = 0; i < w.size(); i += 3) w[i] = 1.0f;
  pull_push_fill(img, w);
  for (std::size_t i = 0; i < w.size(); ++i)
    if (w[i] == 1.0f)
      for (int c = 0; c < 2; ++c) EXPECT_EQ(img.data()[i * 2 + c], orig.data()[i * 2 + c]);
}

TEST(PullPush, HolesInASmoothRampGetNearbyValues) {
  Image img = ramp(64, 48);
  const Image orig = img;
  std::vector<float> w(img.pixel_count(), 1.0f);
  for (int y = 20; y < 26; ++y)
    for (int x = 30; x < 36; ++x) {
      w[std::size_t(y) * 64 + x] = 0.0f;
      img.at(x, y, 0) = img.at(x, y, 1) = std::nanf("");
    }
  pull_push_fill(img, w);
  for (int y = 20; y < 26; ++y)
    for (int x = 30; x < 36; ++x) {
      // Within a few pixels' worth of the ramp's slope.
      EXPECT_NEAR(img.at(x, y, 0), orig.at(x, y, 0), 0.05f);
      EXPECT_NEAR(img.at(x, y, 1), orig.at(x, y, 1), 0.1f);
    }
}

TEST(PullPush, NonFiniteSamplesAreHolesAndNothingValidGivesZero) {
  Image img(5, 4, 1, std::numeric_limits<float>::infinity());
  std::vector<float> w(img.pixel_count(), 1.0f);
  pull_push_fill(img, w);
  for (float v : img.storage()) EXPECT_EQ(v, 0.0f);
}

TEST(ExpandedGrid, MappingIsMonotoneAndInvertible) {
  ExpandedGridParams p;
  p.density = 0.2;
  ExpandedGrid g(320, 200, p);
  EXPECT_GT(g.k(), 0.0);
  double prev = -1;
  for (double d = 0; d < g.unexpanded_radius(); d += 0.37) {
    const double e = g.expand(d);
    EXPECT_GE(e, d - 1e-12);  // never compresses
    EXPECT_GT(e, prev);
    EXPECT_NEAR(g.contract(e), d, 1e-9);
    prev = e;
  }
}

TEST(ExpandedGrid, FoveaIsFullySampledAndDensityIsMet) {
  const int w = 320, h = 200;
  for (double density : {0.1, 0.25, 0.5}) {
    ExpandedGridParams p;
    p.gaze_x = 0.3;
    p.gaze_y = 0.6;
    p.fovea_radius = 0.08;
    p.density = density;
    ExpandedGrid g(w, h, p);
    const auto m = g.mask();
    double n = 0;
    for (auto v : m) n += v;
    EXPECT_NEAR(n / m.size(), density, 0.02) << density;
    const double r0 = 0.08 * std::hypot(double(w), double(h));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (std::hypot(x + 0.5 - 0.3 * w, y + 0.5 - 0.6 * h) < r0 - 1.5) EXPECT_EQ(m[std::size_t(y) * w + x], 1) << x << "," << y;
    // Sampling gets sparser away from the gaze: the far half has fewer samples per pixel.
    double near_n = 0, near_a = 0, far_n = 0, far_a = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const bool near = std::hypot(x - 0.3 * w, y - 0.6 * h) < 2 * r0;
        (near ? near_n : far_n) += m[std::size_t(y) * w + x];
        (near ? near_a : far_a) += 1;
      }
    EXPECT_GT(near_n / near_a, far_n / far_a);
  }
}

TEST(Sparse, FilterFillsHolesMarkedBySampleCount) {
  Frame f;
  f.width = 48;
  f.height = 32;
  f.path = "memory";
  Pass c;
  c.role = Role::Colour;
  c.image = Image(48, 32, 3, 0.25f);
  f.passes.push_back(c);
  ExpandedGridParams p;
  p.density = 0.3;
  const Frame sparse = sparsify(f, ExpandedGrid(48, 32, p).mask());
  auto box = make_filter("box");
  box->set("radius", std::int64_t(0));  // identity: only the fill acts
  box->commit();
  const Image out = box->execute(sparse);
  for (float v : out.storage()) EXPECT_NEAR(v, 0.25f, 1e-6f);
  box->set_text("holes", "none");
  box->commit();
  const Image raw = box->execute(sparse);
  int zeros = 0;
  for (float v : raw.storage()) zeros += v == 0.0f;
  EXPECT_GT(zeros, 0);
}

}  // namespace
}  // namespace mcr
