#include "filters/image/box.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "util/parallel.h"

namespace mcr {

const FilterInfo& BoxFilter::static_info() {
  static const FilterInfo info = [] {
    FilterInfo i;
    i.name = "box";
    i.summary = "Box filter: unweighted mean over a square window";
    i.reference = "baseline";
    i.params = with_common_params({ParamSpec::Int("radius", 2, 0, 64, "half width of the window in pixels (window = 2r+1)")});
    i.required = {Role::Colour};
    i.nonfinite_policy =
        "a pixel with any non-finite RGB value is left out of every window; a window with no finite pixel gives 0";
    return i;
  }();
  return info;
}

Roi BoxFilter::reads(const Roi& roi, int width, int height) const {
  return roi.grown(int(params_.get_int("radius")), width, height);
}

void BoxFilter::run(const Frame& frame, const Image& in, const Roi& roi, Image& out, int nthreads) {
  const int r = int(params_.get_int("radius"));
  const int w = frame.width, h = frame.height;
  // Rows the vertical pass reads, and their horizontal sums (RGB + count) in double:
  // direct sums, not running sums, so a 1e30 outlier cannot leave cancellation
  // error behind in its neighbours.
  const int ry0 = std::max(0, roi.y0 - r), ry1 = std::min(h, roi.y1 + r);
  const int rw = roi.width();
  std::vector<double> rows(std::size_t(ry1 - ry0) * rw * 4);
  parallel_rows(ry0, ry1, nthreads, [&](int y) {
    double* dst = rows.data() + std::size_t(y - ry0) * rw * 4;
    for (int x = roi.x0; x < roi.x1; ++x) {
      double s[4] = {0, 0, 0, 0};
      for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx) {
        const float* p = in.pixel(xx, y);
        if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) continue;
        s[0] += p[0]; s[1] += p[1]; s[2] += p[2]; s[3] += 1;
      }
      std::copy(s, s + 4, dst + std::size_t(x - roi.x0) * 4);
    }
  });
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      double s[4] = {0, 0, 0, 0};
      for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy) {
        const double* q = rows.data() + (std::size_t(yy - ry0) * rw + (x - roi.x0)) * 4;
        for (int c = 0; c < 4; ++c) s[c] += q[c];
      }
      float* o = out.pixel(x, y);
      for (int c = 0; c < 3; ++c) {
        const double v = s[3] > 0 ? s[c] / s[3] : 0.0;
        // The mean of finite floats cannot exceed the largest float; clamp only
        // the double rounding so the cast never gives inf.
        constexpr double kMax = std::numeric_limits<float>::max();
        o[c] = float(std::clamp(v, -kMax, kMax));
      }
    }
  });
}

}  // namespace mcr
