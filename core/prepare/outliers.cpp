#include "prepare/outliers.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "image/luminance.h"
#include "util/parallel.h"

namespace mcr {

namespace {

constexpr double kFloatMax = double(std::numeric_limits<float>::max());

// Y of every pixel of `box`, NaN where a channel is not finite.
struct LuminancePlane {
  Roi box;
  std::vector<double> y;
  LuminancePlane(const Image& colour, const Roi& b, int nthreads) : box(b), y(std::size_t(b.width()) * std::size_t(b.height())) {
    parallel_rows(box.y0, box.y1, nthreads, [&](int yy) {
      for (int x = box.x0; x < box.x1; ++x) {
        const float* q = colour.pixel(x, yy);
        y[index(x, yy)] = finite3(q) ? luminance(q) : std::numeric_limits<double>::quiet_NaN();
      }
    });
  }
  std::size_t index(int x, int yy) const { return std::size_t(yy - box.y0) * std::size_t(box.width()) + std::size_t(x - box.x0); }
  double at(int x, int yy) const { return y[index(x, yy)]; }
};

// The window statistics of the rule (centre excluded, finite pixels only).
struct WindowStats {
  int x0, y0, x1, y1;  // the window, inclusive, clipped at the image
  double mu = 0, var = 0;
  std::size_t n = 0;
};

WindowStats window_sum(const LuminancePlane& lum, int x, int y, int radius, int w, int h) {
  WindowStats s{std::max(0, x - radius), std::max(0, y - radius), std::min(w - 1, x + radius), std::min(h - 1, y + radius)};
  for (int yy = s.y0; yy <= s.y1; ++yy)
    for (int xx = s.x0; xx <= s.x1; ++xx) {
      const double q = lum.at(xx, yy);
      if ((xx != x || yy != y) && !std::isnan(q)) { s.mu += q; ++s.n; }
    }
  return s;
}

// mu (from the sum) and the two-pass variance: no cancellation.
void window_moments(const LuminancePlane& lum, int x, int y, WindowStats& s) {
  s.mu /= double(s.n);
  for (int yy = s.y0; yy <= s.y1; ++yy)
    for (int xx = s.x0; xx <= s.x1; ++xx) {
      const double q = lum.at(xx, yy);
      if ((xx != x || yy != y) && !std::isnan(q)) s.var += (q - s.mu) * (q - s.mu);
    }
}

bool bright_outlier(double yp, const WindowStats& s, double k) {
  const double excess = yp - s.mu;
  return excess > k * std::sqrt(s.var / double(s.n)) && excess > 0.01 * std::fabs(s.mu);
}

}  // namespace

std::size_t clamp_fireflies(Image& colour, int radius, double k, const Roi& roi, int nthreads,
                            const std::vector<std::uint8_t>* keep) {
  const int w = colour.width(), h = colour.height();
  if (!(k > 0) || roi.empty()) return 0;
  const LuminancePlane lum(colour, roi.grown(radius, w, h), nthreads);
  std::vector<std::size_t> row_hits(std::size_t(roi.height()), 0);
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      const double yp = lum.at(x, y);
      if (!(yp > 0)) continue;  // NaN, zero or negative: nothing to clamp
      if (keep && (*keep)[std::size_t(y) * std::size_t(w) + std::size_t(x)]) continue;
      WindowStats s = window_sum(lum, x, y, radius, w, h);
      if (s.n < 3) continue;
      window_moments(lum, x, y, s);
      if (!bright_outlier(yp, s, k)) continue;
      const double lim = s.mu + std::max(k * std::sqrt(s.var / double(s.n)), 0.01 * std::fabs(s.mu));
      if (!(lim > 0) || !std::isfinite(lim)) continue;
      const double scale = lim / yp;  // in (0, 1)
      float* o = colour.pixel(x, y);
      for (int c = 0; c < 3; ++c) o[c] = float(double(o[c]) * scale);
      ++row_hits[std::size_t(y - roi.y0)];
    }
  });
  std::size_t hits = 0;
  for (std::size_t v : row_hits) hits += v;
  return hits;
}

OutlierResult replace_outliers(const Image& colour, int radius, double k, const Roi& region, int nthreads) {
  const int w = colour.width(), h = colour.height();
  OutlierResult res;
  res.colour = colour;
  res.valid.assign(std::size_t(w) * h, 1);
  res.replaced.assign(std::size_t(w) * h, 0);
  if (region.empty()) return res;
  const LuminancePlane lum(colour, region.grown(radius, w, h), nthreads);
  parallel_rows(region.y0, region.y1, nthreads, [&](int y) {
    for (int x = region.x0; x < region.x1; ++x) {
      const double lp = lum.at(x, y);
      WindowStats s = window_sum(lum, x, y, radius, w, h);
      const std::size_t i = std::size_t(y) * w + x;
      float* o = res.colour.pixel(x, y);
      std::uint8_t why = 0;
      if (std::isnan(lp)) {
        if (s.n == 0) {
          o[0] = o[1] = o[2] = 0.0f;
          res.valid[i] = 0;
          continue;
        }
        why = 2;
      } else if (k > 0 && s.n >= 3) {
        window_moments(lum, x, y, s);
        if (bright_outlier(lp, s, k)) why = 1;
      }
      if (!why) continue;
      // Replace by the mean RGB of the same neighbours.
      double sum[3] = {0, 0, 0};
      for (int yy = s.y0; yy <= s.y1; ++yy)
        for (int xx = s.x0; xx <= s.x1; ++xx) {
          if (xx == x && yy == y) continue;
          const float* q = colour.pixel(xx, yy);
          if (!finite3(q)) continue;
          for (int c = 0; c < 3; ++c) sum[c] += double(q[c]);
        }
      for (int c = 0; c < 3; ++c) o[c] = float(std::clamp(sum[c] / double(s.n), -kFloatMax, kFloatMax));
      res.replaced[i] = why;
    }
  });
  return res;
}

void clamp_channels(Image& colour, double lim, const Roi& roi, int nthreads) {
  if (!(lim > 0) || roi.empty()) return;
  const float l = float(std::min(lim, kFloatMax));
  const int ch = colour.channels();
  parallel_rows(roi.y0, roi.y1, nthreads, [&](int y) {
    float* p = colour.pixel(roi.x0, y);
    for (std::size_t i = 0, n = std::size_t(roi.width()) * std::size_t(ch); i < n; ++i)
      if (std::isfinite(p[i])) p[i] = std::min(std::max(p[i], -l), l);
  });
}

}  // namespace mcr
