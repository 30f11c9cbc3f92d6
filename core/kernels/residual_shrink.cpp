#include "kernels/residual_shrink.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "util/parallel.h"

namespace mcr {

namespace {

constexpr int kPlanes = 5;  // finite count, residual R, G, B, sum over R, G, B of its square

}  // namespace

std::size_t add_back_residual(const ResidualSettings& s, const Image& unbiased, const Image* albedo, RgbLayout result,
                              const Roi& roi, std::vector<float>& scratch, int nthreads) {
  const int w = unbiased.width();
  if (roi.empty()) return 0;
  // Everything in the roi's own coordinates: windows clipped to it, nothing outside read
  // or written.
  const int rw = roi.width(), rh = roi.height();
  const std::size_t rn = std::size_t(rw) * std::size_t(rh);
  const std::size_t ps = result.pixel_stride, cs = result.channel_stride;
  auto at = [&](int x, int y, int c) -> float& {
    return result.data[(std::size_t(y) * std::size_t(w) + std::size_t(x)) * ps + std::size_t(c) * cs];
  };
  const int R = s.radius;
  // Row sums over each pixel's window columns, made from the residual of that row on the
  // fly: kPlanes planes of rw x rh (plane-major, so that the sums run over contiguous
  // floats). Short direct sums, not running ones: no rounding carried along a row.
  scratch.resize(rn * kPlanes);
  auto hs = [&](int k, int ry) { return scratch.data() + std::size_t(k) * rn + std::size_t(ry) * std::size_t(rw); };
  parallel_rows(0, rh, nthreads, [&](int ry) {
    thread_local std::vector<float> row;
    row.assign(std::size_t(rw) * kPlanes, 0.0f);
    float* r[kPlanes];
    for (int k = 0; k < kPlanes; ++k) r[k] = row.data() + std::size_t(k) * std::size_t(rw);
    const int y = roi.y0 + ry;
    for (int rx = 0; rx < rw; ++rx) {
      const int x = roi.x0 + rx;
      const float* a = unbiased.pixel(x, y);
      const float* al = albedo ? albedo->pixel(x, y) : nullptr;
      float d[3];
      for (int c = 0; c < 3; ++c) d[c] = a[c] * (al ? al[c] : 1.0f) - at(x, y, c);
      if (!(std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2]))) continue;  // takes no part
      r[0][rx] = 1.0f;
      r[1][rx] = d[0];
      r[2][rx] = d[1];
      r[3][rx] = d[2];
      r[4][rx] = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    }
    for (int k = 0; k < kPlanes; ++k) {
      float* o = hs(k, ry);
      const float* v = r[k];
      std::fill(o, o + rw, 0.0f);
      for (int q = -R; q <= R; ++q)  // offset by offset: contiguous, clipped at the ends
        for (int x = std::max(0, -q), x1 = std::min(rw, rw - q); x < x1; ++x) o[x] += v[x + q];
    }
  });
  std::vector<std::size_t> taken(std::size_t(rh), 0);
  parallel_rows(0, rh, nthreads, [&](int ry) {
    thread_local std::vector<float> col;
    col.assign(std::size_t(rw) * kPlanes, 0.0f);
    const int qy0 = std::max(0, ry - R), qy1 = std::min(rh - 1, ry + R);
    for (int k = 0; k < kPlanes; ++k) {
      float* o = col.data() + std::size_t(k) * std::size_t(rw);
      for (int qy = qy0; qy <= qy1; ++qy) {
        const float* v = hs(k, qy);
        for (int x = 0; x < rw; ++x) o[x] += v[x];
      }
    }
    const float* sum[kPlanes];
    for (int k = 0; k < kPlanes; ++k) sum[k] = col.data() + std::size_t(k) * std::size_t(rw);
    for (int rx = 0; rx < rw; ++rx) {
      const double cnt = sum[0][rx];
      if (!(cnt > 0.0)) continue;
      // In sums (S0 = cnt, Sc, Q): n m_l^2 = (S1 + S2 + S3)^2 / (9 S0) and v_l = (Q S0 - sum
      // Sc^2) / (3 S0^2), so w > 0 exactly when (S1 + S2 + S3)^2 S0 > 3 k (Q S0 - sum Sc^2):
      // most pixels (noise about a right fit) are settled without a division.
      const double s1 = sum[1][rx], s2 = sum[2][rx], s3 = sum[3][rx], st = s1 + s2 + s3;
      const double spread = std::max(double(sum[4][rx]) * cnt - (s1 * s1 + s2 * s2 + s3 * s3), 0.0);
      if (!(st * st * cnt > 3.0 * s.k * spread)) continue;
      const double wt = std::min(1.0 - 3.0 * s.k * spread / (st * st * cnt), 1.0);
      const double m[3] = {s1 / cnt, s2 / cnt, s3 / cnt};
      constexpr double M = std::numeric_limits<float>::max();
      for (int c = 0; c < 3; ++c) {
        float& o = at(roi.x0 + rx, roi.y0 + ry, c);
        o = float(std::clamp(double(o) + wt * m[c], -M, M));
      }
      taken[std::size_t(ry)] += wt > 0.5;
    }
  });
  return std::accumulate(taken.begin(), taken.end(), std::size_t(0));
}

}  // namespace mcr
