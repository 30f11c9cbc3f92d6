// Box filter against closed forms and a plain brute-force window loop.
#include "filters/image/box.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "expect_error.h"
#include "feature_filter_testutil.h"
#include "filters/registry.h"
#include "util/error.h"

namespace mcr {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

Frame frame_of(const Image& colour) {
  Frame f;
  f.width = colour.width();
  f.height = colour.height();
  f.path = "test.exr";
  Pass p;
  p.role = Role::Colour;
  p.name = "Combined";
  p.image = colour;
  f.passes.push_back(p);
  return f;
}

Image random_image(int w, int h, unsigned seed) { return testutil::random_image(w, h, 3, seed); }

Image run_box(const Image& colour, int radius, int nthreads = 0, Roi roi = {}, std::size_t* repaired = nullptr) {
  BoxFilter f;
  testutil::without_step_back(f);
  f.set("radius", std::int64_t(radius));
  f.commit();
  ExecOptions eo;
  eo.nthreads = nthreads;
  eo.roi = roi;
  Image out = f.execute(frame_of(colour), eo);
  if (repaired) *repaired = f.nonfinite_repaired();
  return out;
}

// The mean of the finite pixels in the window clipped at the borders; 0 when none.
void brute_mean(const Image& in, int x, int y, int r, double out[3]) {
  double s[3] = {0, 0, 0};
  int n = 0;
  for (int yy = y - r; yy <= y + r; ++yy)
    for (int xx = x - r; xx <= x + r; ++xx) {
      if (xx < 0 || yy < 0 || xx >= in.width() || yy >= in.height()) continue;
      const float* p = in.pixel(xx, yy);
      if (!testutil::finite_n(p, 3)) continue;
      for (int c = 0; c < 3; ++c) s[c] += p[c];
      ++n;
    }
  for (int c = 0; c < 3; ++c) out[c] = n ? s[c] / n : 0.0;
}

void expect_matches_brute_force(const Image& in, const Image& out, int r) {
  testutil::expect_each_pixel_near(
      in, out, [&](int x, int y, double want[3]) { brute_mean(in, x, y, r, want); }, 1e-6,
      [&](int, int) { return testing::Message() << " radius " << r; });
}

TEST(BoxFilterTest, RadiusZeroIsIdentity) {
  const Image in = random_image(17, 11, 1);
  const Image out = run_box(in, 0);
  EXPECT_EQ(out.storage(), in.storage());
}

TEST(BoxFilterTest, ConstantImageStaysConstant) {
  for (float v : {0.0f, 0.375f, -2.5f, 1e-30f, 1e30f, 3.3e38f, -3.3e38f, std::numeric_limits<float>::max()}) {
    Image in(13, 9, 3, v);
    const Image out = run_box(in, 3);
    for (float o : out.storage()) ASSERT_EQ(o, v) << "constant " << v;
  }
}

TEST(BoxFilterTest, InteriorPixelIsMeanOfFullWindow) {
  // 0..24 in a 5x5 image: the centre with r=2 sees all 25 values, mean 12.
  Image in(5, 5, 3);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 5; ++x)
      for (int c = 0; c < 3; ++c) in.at(x, y, c) = float(y * 5 + x + 100 * c);
  const Image out = run_box(in, 2);
  EXPECT_FLOAT_EQ(out.at(2, 2, 0), 12.0f);
  EXPECT_FLOAT_EQ(out.at(2, 2, 1), 112.0f);
  EXPECT_FLOAT_EQ(out.at(2, 2, 2), 212.0f);
  // Corner (0,0) sees the clipped 3x3 window {0,1,2,5,6,7,10,11,12}: mean 6.
  EXPECT_FLOAT_EQ(out.at(0, 0, 0), 6.0f);
  // Edge (4,2) sees columns 2..4 of every row: mean of 3+5y+{-1,0,1}... = 13.
  EXPECT_FLOAT_EQ(out.at(4, 2, 0), 13.0f);
}

TEST(BoxFilterTest, MatchesBruteForceOnRandomImages) {
  for (int r : {1, 2, 5}) {
    const Image in = random_image(23, 19, 10 + unsigned(r));
    expect_matches_brute_force(in, run_box(in, r), r);
  }
}

TEST(BoxFilterTest, RadiusLargerThanImageGivesGlobalMean) {
  const Image in = random_image(4, 3, 7);
  const Image out = run_box(in, 64);
  double want[3];
  brute_mean(in, 0, 0, 100, want);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.at(x, y, c), want[c], 1e-6);
}

TEST(BoxFilterTest, DegenerateShapes) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{1, 9}, std::pair{9, 1}, std::pair{2, 1}, std::pair{1, 2}}) {
    const Image in = random_image(w, h, unsigned(w * 31 + h));
    for (int r : {0, 1, 3}) {
      SCOPED_TRACE(testing::Message() << w << "x" << h << " r=" << r);
      expect_matches_brute_force(in, run_box(in, r), r);
    }
  }
}

TEST(BoxFilterTest, NonFinitePixelsAreLeftOutOfWindows) {
  Image in = random_image(9, 9, 3);
  in.at(4, 4, 0) = kNaN;                // whole pixel excluded
  in.at(1, 1, 1) = kInf;                // R and B finite, still excluded
  in.at(1, 1, 0) = 1000.0f;
  in.at(7, 2, 2) = -kInf;
  std::size_t repaired = 99;
  const Image out = run_box(in, 1, 0, {}, &repaired);
  EXPECT_EQ(repaired, 0u);
  for (float v : out.storage()) ASSERT_TRUE(std::isfinite(v));
  expect_matches_brute_force(in, out, 1);
  // Neighbour of (1,1): the finite 1000 in R of the excluded pixel must not leak in.
  EXPECT_LT(out.at(1, 0, 0), 1.0f);
  EXPECT_LT(out.at(2, 2, 0), 1.0f);
}

TEST(BoxFilterTest, WindowWithoutFinitePixelGivesZero) {
  Image in(5, 5, 3, kNaN);
  in.at(4, 4, 0) = 2.0f;  // the only finite pixel
  in.at(4, 4, 1) = 4.0f;
  in.at(4, 4, 2) = 6.0f;
  std::size_t repaired = 99;
  const Image out = run_box(in, 1, 0, {}, &repaired);
  EXPECT_EQ(repaired, 0u);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(out.at(0, 0, c), 0.0f);  // window has no finite pixel
  EXPECT_EQ(out.at(3, 3, 0), 2.0f);                              // window holds just (4,4)
  EXPECT_EQ(out.at(3, 3, 2), 6.0f);
  for (float v : out.storage()) ASSERT_TRUE(std::isfinite(v));
}

TEST(BoxFilterTest, AllNonFiniteImageGivesZeros) {
  Image in(4, 3, 3, kInf);
  std::size_t repaired = 99;
  const Image out = run_box(in, 2, 0, {}, &repaired);
  EXPECT_EQ(repaired, 0u);
  for (float v : out.storage()) EXPECT_EQ(v, 0.0f);
}

TEST(BoxFilterTest, HugeOutlierLeavesNoCancellationErrorFarAway) {
  const float tiny = 1e-30f;
  Image in(40, 40, 3, tiny);
  in.at(5, 5, 0) = 1e30f;
  in.at(5, 5, 1) = -1e30f;
  in.at(5, 5, 2) = 1e30f;
  const int r = 2;
  const Image out = run_box(in, r);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) {
      const bool near = std::abs(x - 5) <= r && std::abs(y - 5) <= r;
      if (near) {
        double want[3];
        brute_mean(in, x, y, r, want);
        ASSERT_NEAR(out.at(x, y, 0), want[0], 1e-6 * std::fabs(want[0]));
        ASSERT_NEAR(out.at(x, y, 1), want[1], 1e-6 * std::fabs(want[1]));
      } else {
        // Same row or column as the outlier included: the mean of 1e-30s is exactly 1e-30.
        for (int c = 0; c < 3; ++c) ASSERT_EQ(out.at(x, y, c), tiny) << x << "," << y << " c" << c;
      }
    }
}

TEST(BoxFilterTest, HugeValuesDoNotOverflow) {
  const float big = std::numeric_limits<float>::max();
  Image in(6, 6, 3, big);
  in.at(0, 0, 0) = -big;
  std::size_t repaired = 99;
  const Image out = run_box(in, 2, 0, {}, &repaired);
  EXPECT_EQ(repaired, 0u);
  for (float v : out.storage()) ASSERT_TRUE(std::isfinite(v));
  EXPECT_EQ(out.at(5, 5, 1), big);
}

TEST(BoxFilterTest, ResultIsIdenticalForOneAndTwoThreads) {
  Image in = random_image(64, 37, 5);
  in.at(10, 10, 1) = kNaN;
  const Image one = run_box(in, 3, 1);
  const Image two = run_box(in, 3, 2);
  const Image all = run_box(in, 3, 0);
  EXPECT_EQ(one.storage(), two.storage());
  EXPECT_EQ(one.storage(), all.storage());
}

TEST(BoxFilterTest, RegionChangesOnlyPixelsInside) {
  const Image in = random_image(30, 20, 8);
  const int r = 2;
  const Roi roi{7, 3, 19, 11};
  // Windows reach outside the region: inside, the whole-frame result.
  testutil::expect_only_region_changed(run_box(in, r, 0, roi), run_box(in, r), in, roi);
}

// A region reaching outside the image is refused, not clipped (issue 13: a typo in
// --region must not filter a different region silently); the whole image as a region is fine.
TEST(BoxFilterTest, RegionOutsideTheImageIsRefused) {
  const Image in = random_image(10, 8, 9);
  testutil::expect_error(Errc::InvalidArgument, {"region -5,4,100,100", "10x8"},
                         [&] { run_box(in, 1, 0, Roi{-5, 4, 100, 100}); });
  const Image out = run_box(in, 1, 0, Roi{0, 0, 10, 8});
  const Image full = run_box(in, 1);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 10; ++x)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(out.at(x, y, c), full.at(x, y, c));
}

TEST(BoxFilterTest, ExtraColourChannelsAreDroppedAndAlphaIsNotAveraged) {
  Image in(5, 5, 4, 1.0f);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 5; ++x) in.at(x, y, 3) = kNaN;  // a 4th channel is not part of the RGB policy
  const Image out = run_box(in, 1);
  EXPECT_EQ(out.channels(), 3);
  for (float v : out.storage()) EXPECT_EQ(v, 1.0f);
}

TEST(BoxFilterTest, LifecycleAndParameterErrors) {
  auto f = make_filter("box");
  EXPECT_EQ(f->params().get_int("radius"), 2);
  const Frame frame = frame_of(random_image(4, 4, 1));
  try {
    f->execute(frame);
    FAIL() << "execute before commit must throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::Internal);
  }
  try {
    f->set_text("radius", "65");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::ParameterOutOfRange);
  }
  f->commit();
  Frame empty;
  empty.width = 4;
  empty.height = 4;
  empty.path = "nocolour.exr";
  try {
    f->execute(empty);
    FAIL() << "a frame without colour must throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::MissingPass);
    EXPECT_NE(std::string(e.what()).find("colour"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nocolour.exr"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mcr
