// kernels/feature_activity: constant, varying and absent feature passes over a region.
#include "kernels/feature_activity.h"

#include <gtest/gtest.h>

#include <limits>

namespace mcr {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

Image filled(int w, int h, std::initializer_list<float> v) {
  Image im(w, h, int(v.size()));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) std::copy(v.begin(), v.end(), im.pixel(x, y));
  return im;
}

TEST(FeatureActivity, ConstantPassReportsItsValue) {
  const Image n = filled(37, 29, {0.0f, 0.0f, 1.0f});
  for (int threads : {1, 2, 0}) {
    const FeatureActivity a = feature_activity(n, 3, Roi::all(37, 29), 0.0, threads);
    EXPECT_EQ(a.kind, Activity::Constant);
    EXPECT_FALSE(a.some_nonfinite);
    EXPECT_EQ(a.value[0], 0.0f);
    EXPECT_EQ(a.value[2], 1.0f);
  }
}

TEST(FeatureActivity, OneValueJustOutsideTheToleranceVaries) {
  const double tol = constant_tolerance(0.2);  // 0.0008
  EXPECT_DOUBLE_EQ(tol, 0.0008);
  for (int threads : {1, 2}) {
    Image n = filled(40, 30, {0.0f, 0.0f, 1.0f});
    n.pixel(39, 29)[2] = 1.0f - 0.0009f;  // the last pixel: the whole scan must see it
    EXPECT_EQ(feature_activity(n, 3, Roi::all(40, 30), tol, threads).kind, Activity::Varies);
    n.pixel(39, 29)[2] = 1.0f - 0.0007f;
    EXPECT_EQ(feature_activity(n, 3, Roi::all(40, 30), tol, threads).kind, Activity::Constant);
    n.pixel(17, 3)[0] = 0.00081f;  // any channel
    EXPECT_EQ(feature_activity(n, 3, Roi::all(40, 30), tol, threads).kind, Activity::Varies);
  }
}

TEST(FeatureActivity, AllNonFiniteIsAbsent) {
  Image n = filled(9, 7, {kNaN, kNaN, kNaN});
  n.pixel(3, 3)[0] = 0.5f;  // one finite channel of three: the pixel still does not count
  n.pixel(4, 4)[1] = kInf;
  const FeatureActivity a = feature_activity(n, 3, Roi::all(9, 7), 0.1, 2);
  EXPECT_EQ(a.kind, Activity::Absent);
  EXPECT_EQ(activity_note("normal", a, Roi::all(9, 7), 9, 7, "not used"),
            "normal pass has no finite value over the frame: not used");
}

TEST(FeatureActivity, NonFinitePixelsAreSkippedAndReported) {
  Image d = filled(11, 8, {5.0f});
  d.pixel(0, 0)[0] = kNaN;  // the reference is the first finite pixel
  d.pixel(6, 5)[0] = -kInf;
  const FeatureActivity a = feature_activity(d, 1, Roi::all(11, 8), 0.0, 2);
  EXPECT_EQ(a.kind, Activity::Constant);
  EXPECT_EQ(a.value[0], 5.0f);
  EXPECT_TRUE(a.some_nonfinite);
  d.pixel(0, 0)[0] = 5.0f;
  d.pixel(6, 5)[0] = 5.0f;
  EXPECT_FALSE(feature_activity(d, 1, Roi::all(11, 8), 0.0, 2).some_nonfinite);
}

TEST(FeatureActivity, OnlyTheRegionCounts) {
  Image p = filled(20, 20, {1.0f, 2.0f, 3.0f});
  p.pixel(2, 2)[1] = 7.0f;
  const Roi inner{5, 5, 15, 15};
  EXPECT_EQ(feature_activity(p, 3, inner, 0.0, 2).kind, Activity::Constant);
  EXPECT_EQ(feature_activity(p, 3, Roi::all(20, 20), 0.0, 2).kind, Activity::Varies);
  EXPECT_EQ(activity_note("position", feature_activity(p, 3, inner, 0.0, 2), inner, 20, 20, "dropped"),
            "position pass is constant over the region read (1.000, 2.000, 3.000): dropped");
}

TEST(FeatureActivity, RelativeToleranceScalesWithEachChannel) {
  Image p = filled(8, 8, {1000.0f, 0.0f, 3.0f});
  p.pixel(5, 5)[0] = 1000.004f;  // 4e-6 relative
  EXPECT_EQ(feature_activity(p, 3, Roi::all(8, 8), Tolerance(0.0, 0.49e-5), 1).kind, Activity::Constant);
  p.pixel(5, 5)[1] = 1e-30f;  // channel 1 is 0: any change there varies
  EXPECT_EQ(feature_activity(p, 3, Roi::all(8, 8), Tolerance(0.0, 0.49e-5), 1).kind, Activity::Varies);
}

TEST(FeatureActivity, FewerChannelsRepeatTheLast) {
  Image one(6, 6, 1, 0.25f);
  const FeatureActivity a = feature_activity(one, 3, Roi::all(6, 6), 0.0, 1);
  EXPECT_EQ(a.kind, Activity::Constant);
  EXPECT_EQ(a.value[2], 0.25f);
}

}  // namespace
}  // namespace mcr
