#include "temporal/reprojection.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "util/parallel.h"

namespace mcr {

namespace {

bool finite3(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

double dist2(const float* a, const float* b) {
  const double dx = double(a[0]) - b[0], dy = double(a[1]) - b[1], dz = double(a[2]) - b[2];
  return dx * dx + dy * dy + dz * dz;
}

double norm2(const float* a) { return double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]; }

// Squared world size of pixel (x, y): the larger of the horizontal and vertical distance
// to the nearer neighbour (the nearer one is on the same surface away from edges).
double footprint2(const Image& pos, int x, int y) {
  const float* p = pos.pixel(x, y);
  auto nearest = [&](int ax, int ay, int bx, int by) {
    double d = INFINITY;
    if (ax >= 0 && ay >= 0 && ax < pos.width() && ay < pos.height() && finite3(pos.pixel(ax, ay)))
      d = std::min(d, dist2(p, pos.pixel(ax, ay)));
    if (bx >= 0 && by >= 0 && bx < pos.width() && by < pos.height() && finite3(pos.pixel(bx, by)))
      d = std::min(d, dist2(p, pos.pixel(bx, by)));
    return d;
  };
  const double h = nearest(x - 1, y, x + 1, y), v = nearest(x, y - 1, x, y + 1);
  double f = 0;
  if (std::isfinite(h)) f = std::max(f, h);
  if (std::isfinite(v)) f = std::max(f, v);
  return f;
}

}  // namespace

void GeometryHistory::reset() {
  position_ = Image();
  normal_ = Image();
}

Reprojection GeometryHistory::update(const Image& position, const Image& normal, const Image* motion,
                                     const ReprojectionParams& params, int nthreads) {
  Reprojection r;
  const int w = position.width(), h = position.height();
  r.width = w;
  r.height = h;
  const std::size_t n = position.pixel_count();
  r.prev_x.assign(n, 0.0f);
  r.prev_y.assign(n, 0.0f);
  r.taps.assign(n, 0);
  r.inside.assign(n, 0);
  r.has_history = !position_.empty() && position_.width() == w && position_.height() == h;
  if (motion && (motion->width() != w || motion->height() != h || motion->channels() < 2)) motion = nullptr;

  std::vector<std::size_t> row_discarded(std::size_t(std::max(h, 0)), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    std::size_t lost = 0;
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      float px, py;
      previous_position(motion, x, y, px, py);
      if (!std::isfinite(px) || !std::isfinite(py) || std::fabs(px) > 1e7f || std::fabs(py) > 1e7f) {
        px = -2.0f;  // far outside: no tap
        py = -2.0f;
      }
      r.prev_x[i] = px;
      r.prev_y[i] = py;
      if (!r.has_history) {
        ++lost;
        continue;
      }
      const int x0 = int(std::floor(px)), y0 = int(std::floor(py));
      const float* pc = position.pixel(x, y);
      const float* nc = normal.pixel(x, y);
      const bool pos_ok = finite3(pc);
      const double ncl = finite3(nc) ? norm2(nc) : -1.0;  // squared length
      // Squared distance limit.
      double limit = params.position_threshold * params.position_threshold;
      if (pos_ok && params.relative_position) limit *= footprint2(position, x, y);
      if (pos_ok) {
        const double floor = 1e-6 * (1.0 + std::sqrt(norm2(pc)));  // float rounding of the positions
        limit = std::max(limit, floor * floor);
      }
      const double cs = params.normal_cos;
      std::uint8_t mask = 0, in = 0;
      for (int k = 0; k < 4; ++k) {
        const int tx = x0 + (k & 1), ty = y0 + (k >> 1);
        if (tx < 0 || ty < 0 || tx >= w || ty >= h) continue;
        in |= std::uint8_t(1u << k);
        if (!pos_ok || ncl < 0) continue;
        const float* pp = position_.pixel(tx, ty);
        const float* np = normal_.pixel(tx, ty);
        if (!finite3(pp) || !finite3(np)) continue;
        if (!(dist2(pc, pp) <= limit)) continue;
        const double npl = norm2(np);
        if (ncl < 1e-6 && npl < 1e-6) {
          // both background / no normal: agree
        } else {
          if (ncl < 1e-6 || npl < 1e-6) continue;
          // cos >= cs without square roots: d >= cs |a||b|.
          const double d = double(nc[0]) * np[0] + double(nc[1]) * np[1] + double(nc[2]) * np[2];
          const double ab = ncl * npl;
          const bool ok = cs >= 0 ? (d >= 0 && d * d >= cs * cs * ab) : (d >= 0 || d * d <= cs * cs * ab);
          if (!ok) continue;
        }
        mask |= std::uint8_t(1u << k);
      }
      r.taps[i] = mask;
      r.inside[i] = in;
      if (!mask) ++lost;
    }
    row_discarded[std::size_t(y)] = lost;
  });
  for (std::size_t v : row_discarded) r.discarded += v;
  if (r.has_history && n > 0 && double(r.discarded) > params.cut_fraction * double(n)) {
    r.cut = true;
    std::fill(r.taps.begin(), r.taps.end(), 0);
    std::fill(r.inside.begin(), r.inside.end(), 0);
  }
  position_ = position.channels() == 3 ? position : position.channel_range(0, 3);
  normal_ = normal.channels() == 3 ? normal : normal.channel_range(0, 3);
  return r;
}

}  // namespace mcr
