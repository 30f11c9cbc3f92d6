#include "temporal/reprojection.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "temporal/reprojection_avx2.h"
#include "util/parallel.h"

namespace mcr {

namespace {

}  // namespace

void GeometryHistory::reset() {
  geo_.clear();
  next_geo_.clear();
  geo_w_ = geo_h_ = 0;
}

void GeometryHistory::begin(const Image& position, const Image& normal, const Image*& motion, Reprojection& r) {
  (void)normal;
  const int w = position.width(), h = position.height();
  r.width = w;
  r.height = h;
  const std::size_t n = position.pixel_count();
  // resize() keeps the storage of the previous frame: every entry is rewritten by row().
  r.prev_x.resize(n);
  r.prev_y.resize(n);
  r.taps.resize(n);
  r.inside.resize(n);
  r.has_history = !geo_.empty() && geo_w_ == w && geo_h_ == h && geo_.size() == n * kGeoRecord;
  r.cut = false;
  r.discarded = 0;
  if (motion && (motion->width() != w || motion->height() != h || motion->channels() < 2)) motion = nullptr;
  next_geo_.resize(n * kGeoRecord);
}

std::size_t GeometryHistory::row(int y, const Image& position, const Image& normal, const Image* motion,
                                 const ReprojectionParams& params, Reprojection& r) {
  const int w = r.width, h = r.height;
  const int pc_ch = position.channels(), nc_ch = normal.channels();
  const float* prow = position.data() + std::size_t(y) * w * pc_ch;
  const float* nrow = normal.data() + std::size_t(y) * w * nc_ch;
  float* grow = next_geo_.data() + std::size_t(y) * w * kGeoRecord;
  // The AVX2 path (same results) takes the bulk of the row, 8 pixels at a time, and
  // stores those pixels' records itself; the scalar loops do the rest.
  const bool vec = r.has_history && pc_ch == 3 && nc_ch == 3 && w > 10 && detail::tap_row_avx2_available();
  const int vx0 = vec ? 1 : 0, vx1 = vec ? 1 + (w - 2) / 8 * 8 : 0;
  // This row's records for the next frame.
  for (int x = 0; x < w; ++x) {
    if (x == vx0 && vx1 > vx0) x = vx1;
    const float* p = prow + std::size_t(x) * pc_ch;
    const float* q = nrow + std::size_t(x) * nc_ch;
    float* g = grow + std::size_t(x) * kGeoRecord;
    const float fin = (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]) + (q[0] - q[0]) + (q[1] - q[1]) + (q[2] - q[2]);
    const float l = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
    g[0] = p[0];
    g[1] = p[1];
    g[2] = p[2];
    g[3] = q[0];
    g[4] = q[1];
    g[5] = q[2];
    g[6] = fin == 0.0f ? l : std::numeric_limits<float>::quiet_NaN();
    g[7] = 0.0f;
  }
  const float* mrow = motion ? motion->data() + std::size_t(y) * w * motion->channels() : nullptr;
  const int mch = motion ? motion->channels() : 0;
  const float* hg = geo_.data();
  // Float arithmetic on differences: the tests compare distances of neighbouring
  // surface points, where float is ample; overflowing magnitudes read as "far".
  const float thr2 = float(params.position_threshold * params.position_threshold);
  const float cs = float(params.normal_cos), cs2 = cs * cs;
  const bool relative = params.relative_position;
  // x - x is 0 for finite x, NaN otherwise.
  auto fin3 = [](const float* p) { return ((p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2])) == 0.0f; };
  auto d2 = [](const float* a, const float* b) {
    const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
  };
  const std::size_t rs = std::size_t(w) * std::size_t(pc_ch);
  std::size_t lost = 0;
  if (vec) {
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    const detail::TapRow a{w, h, y, prow, nrow, grow, mrow, mch, hg, thr2, cs, cs2, relative,
                           r.prev_x.data() + rb, r.prev_y.data() + rb, r.taps.data() + rb, r.inside.data() + rb};
    lost += detail::tap_row_avx2(a, vx0, vx1);
  }
  for (int x = 0; x < w; ++x) {
    if (x == vx0 && vx1 > vx0) x = vx1;
    const std::size_t i = std::size_t(y) * w + x;
    float px = float(x), py = float(y);
    if (mrow) {
      px += mrow[std::size_t(x) * mch];
      py -= mrow[std::size_t(x) * mch + 1];
    }
    if (!(std::fabs(px) <= 1e7f) || !(std::fabs(py) <= 1e7f)) {  // also NaN
      px = -2.0f;  // far outside: no tap
      py = -2.0f;
    }
    r.prev_x[i] = px;
    r.prev_y[i] = py;
    if (!r.has_history) {
      r.taps[i] = 0;
      r.inside[i] = 0;
      ++lost;
      continue;
    }
    const int x0 = floor_int(px), y0 = floor_int(py);
    std::uint8_t in = 0;
    for (int k = 0; k < 4; ++k) {
      const int tx = x0 + (k & 1), ty = y0 + (k >> 1);
      if (tx >= 0 && ty >= 0 && tx < w && ty < h) in |= std::uint8_t(1u << k);
    }
    r.inside[i] = in;
    const float* pc = prow + std::size_t(x) * pc_ch;
    const float* nc = nrow + std::size_t(x) * nc_ch;
    const float ncl = grow[std::size_t(x) * kGeoRecord + 6];  // squared normal length; NaN: non-finite position or normal
    if (!in || ncl != ncl) {
      r.taps[i] = 0;
      ++lost;
      continue;
    }
    // Squared distance limit.
    float limit = thr2;
    if (relative) {
      // Footprint: the larger of the horizontal and vertical distance to the nearer
      // finite neighbour.
      float fh = INFINITY, fv = INFINITY;
      if (x > 0 && fin3(pc - pc_ch)) fh = d2(pc, pc - pc_ch);
      if (x + 1 < w && fin3(pc + pc_ch)) fh = std::min(fh, d2(pc, pc + pc_ch));
      if (y > 0 && fin3(pc - rs)) fv = d2(pc, pc - rs);
      if (y + 1 < h && fin3(pc + rs)) fv = std::min(fv, d2(pc, pc + rs));
      float f = 0;
      if (fh < INFINITY) f = std::max(f, fh);
      if (fv < INFINITY) f = std::max(f, fv);
      limit *= f;
    }
    {
      const float floor = 1e-6f * (1.0f + std::sqrt(pc[0] * pc[0] + pc[1] * pc[1] + pc[2] * pc[2]));  // float rounding
      limit = std::max(limit, floor * floor);
    }
    std::uint8_t mask = 0;
    for (int k = 0; k < 4; ++k) {
      if (!(in & (1u << k))) continue;
      const std::size_t ti = std::size_t(y0 + (k >> 1)) * w + std::size_t(x0 + (k & 1));
      const float* pp = hg + ti * kGeoRecord;
      const float* np = pp + 3;
      const float npl = pp[6];
      if (npl != npl) continue;  // non-finite history position or normal
      if (!(d2(pc, pp) <= limit)) continue;
      if (ncl < 1e-6f && npl < 1e-6f) {
        // both background / no normal: agree
      } else {
        if (ncl < 1e-6f || npl < 1e-6f) continue;
        // cos >= cs without square roots: d >= cs |a||b|.
        const float d = nc[0] * np[0] + nc[1] * np[1] + nc[2] * np[2];
        const float ab = ncl * npl;
        const bool ok = cs >= 0 ? (d >= 0 && d * d >= cs2 * ab) : (d >= 0 || d * d <= cs2 * ab);
        if (!ok) continue;
      }
      mask |= std::uint8_t(1u << k);
    }
    r.taps[i] = mask;
    if (!mask) ++lost;
  }
  return lost;
}

bool GeometryHistory::finish(const ReprojectionParams& params, Reprojection& r, std::size_t discarded) {
  const std::size_t n = std::size_t(r.width) * std::size_t(r.height);
  r.discarded = discarded;
  if (r.has_history && n > 0 && double(r.discarded) > params.cut_fraction * double(n)) {
    r.cut = true;
    std::fill(r.taps.begin(), r.taps.end(), 0);
    std::fill(r.inside.begin(), r.inside.end(), 0);
  }
  std::swap(geo_, next_geo_);
  geo_w_ = r.width;
  geo_h_ = r.height;
  return r.cut;
}

void GeometryHistory::update(const Image& position, const Image& normal, const Image* motion,
                             const ReprojectionParams& params, int nthreads, Reprojection& r) {
  begin(position, normal, motion, r);
  const int h = position.height();
  std::vector<std::size_t> row_discarded(std::size_t(std::max(h, 0)), 0);
  parallel_rows(0, h, nthreads, [&](int y) { row_discarded[std::size_t(y)] = row(y, position, normal, motion, params, r); });
  std::size_t d = 0;
  for (std::size_t v : row_discarded) d += v;
  finish(params, r, d);
}

Reprojection GeometryHistory::update(const Image& position, const Image& normal, const Image* motion,
                                     const ReprojectionParams& params, int nthreads) {
  Reprojection r;
  update(position, normal, motion, params, nthreads, r);
  return r;
}

}  // namespace mcr
