// io/half_buffers: the mean and the variance pass of two half buffers, against known noise
// and against the sample renders' halves, their 16-spp file and their reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "feature_filter_testutil.h"
#include "io/frame_reader.h"
#include "io/half_buffers.h"
#include "io/sample_manifest.h"
#include "kernels/noise_scale.h"
#include "util/error.h"

namespace mcr {
namespace {

TEST(HalfBuffers, MeanAndVarianceOfTheMeanOnKnownNoise) {
  const int w = 96, h = 64;
  const double s = 0.2;  // per half
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, float(s));
  Image a(w, h, 4, 1.0f), b(w, h, 4, 1.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = 0.5f + 0.01f * float(x);
        a.at(x, y, c) = v + noise(rng);
        b.at(x, y, c) = v + noise(rng);
      }
  Frame fa = testutil::colour_frame(a), fb = testutil::colour_frame(b);
  fa.path = "a.exr";
  fb.path = "b.exr";
  const Frame f = combine_halves(fa, fb);
  const Image& m = f.image(Role::Colour);
  const Image& v = f.image(Role::Variance);
  double mean_v = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(m.at(x, y, c), 0.5f * a.at(x, y, c) + 0.5f * b.at(x, y, c));
        mean_v += v.at(x, y, c);
      }
      EXPECT_EQ(m.at(x, y, 3), 1.0f);  // alpha from the first
    }
  mean_v /= 3.0 * w * h;
  EXPECT_NEAR(mean_v / (s * s / 2), 1.0, 0.05);  // the variance of the mean of two halves
  Frame small = testutil::colour_frame(Image(10, 10, 3));
  small.path = "small.exr";
  try {
    combine_halves(fa, small);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::SizeMismatch);
    EXPECT_NE(std::string(e.what()).find("small.exr"), std::string::npos);
  }
}

// The sample scenes' halves: their mean is the 16-spp file, and the variance they give is
// within 1.5x of |16 spp - reference|^2 at the median 16x16 tile.
TEST(HalfBuffers, SampleHalvesGiveThe16SppRenderAndItsNoise) {
  int checked = 0;
  for (const SampleScene& sc : load_sample_manifest(std::string(MCRECON_SOURCE_DIR) + "/samples/data")) {
    for (const auto& [spp, pair] : sc.halves) {
      SCOPED_TRACE(pair.first);
      const Frame f = combine_halves(read_frame(pair.first), read_frame(pair.second));
      const Image full = read_frame(sc.noisy.at(spp)).image(Role::Colour);
      const Image ref = read_frame(sc.reference).image(Role::Colour);
      const Image& y = f.image(Role::Colour);
      double worst = 0;
      for (int yy = 0; yy < y.height(); ++yy)
        for (int x = 0; x < y.width(); ++x)
          for (int c = 0; c < 3; ++c)
            worst = std::max(worst, std::abs(double(y.at(x, yy, c)) - full.at(x, yy, c)) / (std::abs(full.at(x, yy, c)) + 1e-3));
      EXPECT_LT(worst, 2e-3);  // half-float rounding of three files
      const NoiseScales ns = estimate_noise_scales(y, Roi::all(y.width(), y.height()), 0, &f.image(Role::Variance));
      std::vector<double> ratio;
      for (int ty = 0; ty + 16 <= y.height(); ty += 16)
        for (int tx = 0; tx + 16 <= y.width(); tx += 16) {
          double e = 0, t = 0;
          for (int yy = ty; yy < ty + 16; ++yy)
            for (int x = tx; x < tx + 16; ++x) {
              e += ns.variance[ns.at(x, yy)];
              for (int c = 0; c < 3; ++c) t += std::pow(double(full.at(x, yy, c)) - ref.at(x, yy, c), 2) / 3;
            }
          if (t > 0 && e > 0) ratio.push_back(std::log2(e / t));
        }
      std::nth_element(ratio.begin(), ratio.begin() + long(ratio.size() / 2), ratio.end());
      EXPECT_LT(std::abs(ratio[ratio.size() / 2]), std::log2(1.5));
      // The reader does the same when given the second half.
      ReadOptions ro;
      ro.second_half = pair.second;
      EXPECT_EQ(read_frame(pair.first, ro).image(Role::Colour).storage(), y.storage());
      EXPECT_EQ(loose_pass_files(ro), std::vector<std::string>{pair.second});  // an input: never an output
      ++checked;
    }
  }
  EXPECT_GE(checked, 3);
}

}  // namespace
}  // namespace mcr
