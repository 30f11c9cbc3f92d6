#pragma once
// Whether a feature pass carries information over the region a filter reads: the one
// test behind "skip what a scene doesn't need" (a flat wall facing the camera has one
// normal and one depth everywhere). The feature-aware filters (bilateral, atrous,
// guided, pwaf, bmfr) drop a constant or absent pass from their weights, guides or
// regressions, with a note that says so, and run faster at the same output.
//
// A pixel counts when every channel read is finite. The pass is
//   Absent    no pixel of the region counts (every value NaN/Inf),
//   Constant  every counted pixel lies, channel by channel, within `tol` of the first
//             counted one (row-major order) within the Tolerance below,
//   Varies    otherwise (the scan stops at the first pixel outside).
// The answer does not depend on the thread count.
//
// Tolerances. A weight exp(-|d|^2 / (2 sigma^2)) of a feature whose channels each
// spread over at most t differs from 1 by at most |d|^2 / (2 sigma^2) with
// |d| <= 2 sqrt(3) t (pairs of pixels, 3 channels): with t = 0.004 sigma that is
// 9.6e-5, so dropping the weight changes no weight by more than 1e-4 relative.
// Filters without a sigma for the feature use their own scale (see each caller); those
// that normalise a guide or a regression column by its own spread (guided's depth and
// position, bmfr) can only call float rounding constant: a relative tolerance.
#include <string>

#include "image/image.h"

namespace mcr {

enum class Activity { Varies, Constant, Absent };

struct FeatureActivity {
  Activity kind = Activity::Absent;
  int channels = 0;
  float value[4] = {0, 0, 0, 0};  // Constant, Varies: the first counted pixel's channels
  bool some_nonfinite = false;    // Constant: some pixel of the region did not count
};

// Channel c of a pixel counts as equal to the reference r_c when |v_c - r_c| <= abs + rel |r_c|.
struct Tolerance {
  double abs = 0, rel = 0;
  Tolerance(double a = 0, double r = 0) : abs(a), rel(r) {}  // NOLINT: a plain number is an absolute tolerance
};

// Fraction of a feature's sigma below which its spread makes the weight constant.
inline constexpr double kConstantSigmaFraction = 0.004;
inline double constant_tolerance(double sigma) { return kConstantSigmaFraction * sigma; }

// Reads channels [0, channels) of `im` (the last channel repeated when it has fewer),
// channels in 1..4, over `region` (inside the image). An image that holds a band of a frame
// in a tiled run (Image::whole_frame, for these channels) is answered for the whole frame,
// whatever the region: the answer the whole frame's run gets (its region is the frame).
FeatureActivity feature_activity(const Image& im, int channels, const Roi& region, const Tolerance& tol,
                                 int nthreads);

// The same answer from a frame's range (exact: the scan's float test is monotonic).
FeatureActivity activity_over_frame(const WholeFrameRange& range, const Tolerance& tol);
// Adds rows of a band (in row-major order of the frame: bands in order) to a frame's range.
void extend_frame_range(const Image& im, int channels, const Roi& rows, WholeFrameRange& range);

// "normal pass is constant over the frame (0.000, 0.000, 1.000): normal weight not used",
// or "... has no finite value over ...". `region` names where ("the frame" when the region
// is the whole w x h frame, else the region read).
std::string activity_note(const std::string& pass, const FeatureActivity& a, const Roi& region, int w, int h,
                          const std::string& consequence);

}  // namespace mcr
