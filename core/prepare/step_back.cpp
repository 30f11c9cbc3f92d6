#include "prepare/step_back.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "kernels/noise_scale.h"
#include "kernels/window_sums.h"
#include "util/parallel.h"

namespace mcr {

namespace {

constexpr double kRangeSigmas = 2.0;    // how far the blend may leave the 3x3 input range
// With a variance pass the weight is also taken over a window this many times as wide, and the
// larger of the two kept (below).
constexpr int kPassWideFactor = 2;
constexpr float kMax = 3.402823466e38f;

double clamp_float(double v) { return std::min(std::max(v, -double(kMax)), double(kMax)); }

// The blend weight from a window's sums: Stein's s^2 / |f - y|^2, at most 1 (1 where f = y).
double weight(double num, double den) { return den > 0 ? std::min(num / den, 1.0) : 1.0; }

}  // namespace

StepBackStats step_back(const Image& input, const Roi& roi_in, int radius, int nthreads, Image& out,
                        const Image* variance, double noise_scale, const Image* modulation, double metric_eps) {
  // A variance pass is each pixel's own: exact in expectation, it is not scaled.
  const double scale = variance ? 1.0 : std::min(std::max(noise_scale, 0.0), 2.0);
  StepBackStats st;
  const int W = input.width(), H = input.height();
  const Roi roi = roi_in.clipped(W, H);
  if (roi.empty()) return st;
  const NoiseScales ns = estimate_noise_scales(input, roi, nthreads, variance, modulation);
  const int rw = roi.width(), rh = roi.height();

  // The window sums of the blend weight's numerator and denominator, over the roi only
  // (outside it the result is the input).
  // Kept between frames (no fresh pages each time); referenced by name here, because a
  // thread_local named inside the parallel lambdas would be each worker's own.
  thread_local WindowSums num_kept, den_kept;
  WindowSums& num = num_kept;
  WindowSums& den = den_kept;
  num.reset(rw, rh, false);
  den.reset(rw, rh, false);
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t i = ns.at(x, y);
      if (!ns.finite[i] || ns.outlier[i]) continue;
      const float* m = &ns.median[i * 3];
      const float* p = input.pixel(x, y);
      const float* f = out.pixel(x, y);
      double nv = 0, dv = 0;
      for (int c = 0; c < 3; ++c) {
        const double w = 1.0 / (double(m[c]) * m[c] + metric_eps);
        const double d = double(f[c]) - double(p[c]);
        nv += w * scale * ns.variance_of(i, c);
        dv += w * d * d;
      }
      num.set(x - roi.x0, y - roi.y0, nv);
      den.set(x - roi.x0, y - roi.y0, std::min(dv, 1e300));
    }
  });
  // With a variance pass, a pixel's own variance is one draw ((A - B)^2 / 4 of two halves: a
  // chi-square of one degree per channel, heavy-tailed at few samples), so over (2 radius + 1)^2
  // pixels the ratio sum v / sum |f - y|^2 still scatters around the truth, and where the filter
  // beats the input everywhere (a ~ 1) every window that reads low blends back some of the input's
  // noise, which is many times the result's (the room still's halves at 16 spp: atrous 0.030 alone,
  // 0.040 stepped back; the truth's own weights give 0.030). The wider window's ratio scatters
  // less and still sees a bias that spans it (light spread from a highlight); a pixel steps back
  // only as far as the less sure of the two asks. Without a pass the estimate is a window mean
  // already, and noise_scale covers the rest.
  thread_local WindowSums numw_kept, denw_kept;
  WindowSums& numw = numw_kept;
  WindowSums& denw = denw_kept;
  const bool wide = variance != nullptr;
  if (wide) {
    numw = num;
    denw = den;
    numw.sum_windows(kPassWideFactor * radius, nthreads);
    denw.sum_windows(kPassWideFactor * radius, nthreads);
  }
  num.sum_windows(radius, nthreads);
  den.sum_windows(radius, nthreads);

  std::vector<double> row_weight(std::size_t(rh), 0.0), row_input(std::size_t(rh), 0.0), row_count(std::size_t(rh), 0.0),
      row_fire(std::size_t(rh), 0.0);
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    const std::size_t ry = std::size_t(y - roi.y0);
    for (int x = roi.x0; x < roi.x1; ++x) {
      const std::size_t i = ns.at(x, y);
      if (!ns.finite[i]) continue;  // the filter's (finite) value stays
      float* f = out.pixel(x, y);
      row_count[ry] += 1;
      if (ns.outlier[i]) {
        row_weight[ry] += 1;
        row_fire[ry] += 1;
        continue;
      }
      const float* p = input.pixel(x, y);
      const float* m = &ns.median[i * 3];
      const double n = num.value(x - roi.x0, y - roi.y0), d = den.value(x - roi.x0, y - roi.y0);
      double a = weight(n, d);
      if (wide) a = std::max(a, weight(numw.value(x - roi.x0, y - roi.y0), denw.value(x - roi.x0, y - roi.y0)));
      for (int c = 0; c < 3; ++c) {
        const double e = double(f[c]) - double(m[c]);
        const double limit = kOutlierSigmas * kOutlierSigmas * ns.robust(i, c);
        if (e * e > limit) a = std::min(a, limit / (e * e));
      }
      // The 3x3 input range (fireflies as their median), widened by kRangeSigmas.
      double lo[3], hi[3];
      for (int c = 0; c < 3; ++c) lo[c] = hi[c] = p[c];
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int qx = x + dx, qy = y + dy;
          if (!roi.contains(qx, qy)) continue;
          const std::size_t j = ns.at(qx, qy);
          if (!ns.finite[j]) continue;
          const float* q = ns.outlier[j] ? &ns.median[j * 3] : input.pixel(qx, qy);
          for (int c = 0; c < 3; ++c) {
            lo[c] = std::min(lo[c], double(q[c]));
            hi[c] = std::max(hi[c], double(q[c]));
          }
        }
      for (int c = 0; c < 3; ++c) {
        const double widen = kRangeSigmas * std::sqrt(ns.robust(i, c));
        const double v = double(p[c]) + a * (double(f[c]) - double(p[c]));
        f[c] = float(clamp_float(std::min(std::max(v, lo[c] - widen), hi[c] + widen)));
      }
      row_weight[ry] += a;
      if (a < 0.5) row_input[ry] += 1;
    }
  });
  double wsum = 0, isum = 0, count = 0, fire = 0;
  for (std::size_t r = 0; r < row_count.size(); ++r) {
    wsum += row_weight[r];
    isum += row_input[r];
    count += row_count[r];
    fire += row_fire[r];
  }
  if (count > 0) {
    st.mean_weight = wsum / count;
    st.input_share = isum / count;
  }
  st.fireflies = std::size_t(fire);
  return st;
}

}  // namespace mcr
