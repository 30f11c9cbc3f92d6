// The pipeline's accumulation stage (pipeline/reconstruction.h) against the closed form
// of BMFR's phase I on a static scene: the cumulative average while 1/n >= alpha, then
// the exponential average of weight alpha.
#include "pipeline/reconstruction.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "feature_filter_testutil.h"
#include "util/isa.h"

namespace mcr {
namespace {

// Frame k of a static shot: fixed geometry (a plane facing the camera), new noise on a
// fixed checkerboard (0.1 / 0.9). Every window then holds both squares, so no sample
// exceeds its neighbours' mean + 3 deviations and the accumulation's sample limit
// (prepare/history_guards.h, tested on its own) cuts none: the closed form holds exactly.
// Plain uniform noise has a pixel above that bound now and then (the limit cut one).
Frame static_frame(int w, int h, int k) {
  Image colour = testutil::random_image(w, h, 3, 100u + unsigned(k), -0.05f, 0.05f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) colour.at(x, y, c) += (x + y) % 2 ? 0.9f : 0.1f;
  Frame f = testutil::colour_frame(std::move(colour));
  Image pos(w, h, 3), nrm(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      pos.at(x, y, 0) = float(x) * 0.1f;
      pos.at(x, y, 1) = float(y) * 0.1f;
      pos.at(x, y, 2) = 5.0f;
      nrm.at(x, y, 2) = 1.0f;
    }
  testutil::add_pass(f, Role::Position, std::move(pos));
  testutil::add_pass(f, Role::Normal, std::move(nrm));
  return f;
}

TEST(Reconstruction, AccumulationOfAStaticShotIsTheClosedForm) {
  const int w = 13, h = 9, frames = 9;
  const double alpha = 0.2;  // AccumulationParams' default (BMFR alpha1)
  for (Isa level : {Isa::Generic, Isa::Avx2}) {
    if (int(level) > int(best_isa())) continue;
    const ScopedIsa use(level);
    SCOPED_TRACE(isa_name(level));
    // box r=0 without the outlier step (on by default): the identity.
    Reconstruction rec(make_committed_filter("box", {{"radius", "0"}, {"firefly_k", "0"}}), true);
    std::vector<double> expect(std::size_t(w) * h * 3, 0.0);
    for (int k = 1; k <= frames; ++k) {
      const Frame f = static_frame(w, h, k);
      const Image out = rec.run(f);
      const double wgt = std::max(1.0 / k, alpha);
      const Image& in = f.image(Role::Colour);
      for (std::size_t i = 0; i < expect.size(); ++i) {
        expect[i] = (1.0 - wgt) * expect[i] + wgt * double(in.storage()[i]);
        ASSERT_NEAR(out.storage()[i], expect[i], 2e-6) << "frame " << k << " value " << i;
      }
    }
    // reset(): the next frame starts a new history (its own colour).
    rec.reset();
    const Frame f = static_frame(w, h, 50);
    EXPECT_EQ(rec.run(f).storage(), f.image(Role::Colour).storage());
  }
}

// alpha=filter with accumulation: the alpha keeps a history of its own, the same closed form.
TEST(Reconstruction, TheAlphaIsAccumulatedByItsOwnHistory) {
  const int w = 13, h = 9, frames = 7;
  const double weight_floor = 0.2;
  Reconstruction rec(make_committed_filter("box", {{"radius", "0"}, {"firefly_k", "0"}}), true);
  std::vector<double> expect(std::size_t(w) * h, 0.0);
  for (int k = 1; k <= frames; ++k) {
    Frame f = static_frame(w, h, k);
    const Image coverage = static_frame(w, h, 100 + k).image(Role::Colour).channel_range(0, 1);
    testutil::add_pass(f, Role::Alpha, coverage);
    Image alpha;
    rec.run(f, {}, nullptr, &alpha);
    ASSERT_EQ(alpha.pixel_count(), expect.size());
    const double wgt = std::max(1.0 / k, weight_floor);
    for (std::size_t i = 0; i < expect.size(); ++i) {
      expect[i] = (1.0 - wgt) * expect[i] + wgt * double(coverage.storage()[i]);
      ASSERT_NEAR(alpha.storage()[i], expect[i], 2e-6) << "frame " << k << " pixel " << i;
    }
  }
}

TEST(Reconstruction, WithoutAccumulationItIsTheFilter) {
  const Frame f = static_frame(11, 7, 1);
  Reconstruction rec(make_committed_filter("box", {{"radius", "2"}}), false);
  EXPECT_FALSE(rec.temporal());
  EXPECT_EQ(rec.run(f).storage(), make_committed_filter("box", {{"radius", "2"}})->execute(f).storage());
  EXPECT_EQ(rec.parameters_text().find("accumulate"), std::string::npos);
  Reconstruction acc(make_committed_filter("box", {}), true);
  EXPECT_TRUE(acc.temporal());
  EXPECT_EQ(acc.parameters_text().rfind("accumulate=true ", 0), 0u);
}

}  // namespace
}  // namespace mcr
