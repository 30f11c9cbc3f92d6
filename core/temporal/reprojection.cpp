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
  position_ = Image();
  normal_ = Image();
  next_position_ = Image();
  next_normal_ = Image();
  info_.clear();
  next_info_.clear();
}

namespace {
void ensure(Image& im, int w, int h, int ch) {
  if (im.width() != w || im.height() != h || im.channels() != ch) im = Image(w, h, ch);
}
}  // namespace

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
  r.has_history = !position_.empty() && position_.width() == w && position_.height() == h && info_.size() == n;
  r.cut = false;
  r.discarded = 0;
  if (motion && (motion->width() != w || motion->height() != h || motion->channels() < 2)) motion = nullptr;
  ensure(next_position_, w, h, 3);
  ensure(next_normal_, w, h, 3);
  next_info_.resize(n);
}

std::size_t GeometryHistory::row(int y, const Image& position, const Image& normal, const Image* motion,
                                 const ReprojectionParams& params, Reprojection& r) {
  const int w = r.width, h = r.height;
  const int pc_ch = position.channels(), nc_ch = normal.channels();
  const float* prow = position.data() + std::size_t(y) * w * pc_ch;
  const float* nrow = normal.data() + std::size_t(y) * w * nc_ch;
  // Keep this row of the current geometry for the next frame.
  {
    float* dp = next_position_.data() + std::size_t(y) * w * 3;
    float* dn = next_normal_.data() + std::size_t(y) * w * 3;
    if (pc_ch == 3)
      std::copy(prow, prow + std::size_t(w) * 3, dp);
    else
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) dp[x * 3 + c] = prow[std::size_t(x) * pc_ch + c];
    if (nc_ch == 3)
      std::copy(nrow, nrow + std::size_t(w) * 3, dn);
    else
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) dn[x * 3 + c] = nrow[std::size_t(x) * nc_ch + c];
  }
  // Per pixel of the stored row: the squared normal length when position and normal are
  // finite, NaN otherwise (read by the tap tests of the next frame, and below).
  {
    const float* dp = next_position_.data() + std::size_t(y) * w * 3;
    const float* dn = next_normal_.data() + std::size_t(y) * w * 3;
    float* inf = next_info_.data() + std::size_t(y) * w;
    for (int x = 0; x < w; ++x) {
      const float* p = dp + std::size_t(x) * 3;
      const float* q = dn + std::size_t(x) * 3;
      const float fin = (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]) + (q[0] - q[0]) + (q[1] - q[1]) + (q[2] - q[2]);
      const float l = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
      inf[x] = fin == 0.0f ? l : std::numeric_limits<float>::quiet_NaN();
    }
  }
  const float* cinfo = next_info_.data() + std::size_t(y) * w;
  const float* hinfo = info_.data();
  const float* mrow = motion ? motion->data() + std::size_t(y) * w * motion->channels() : nullptr;
  const int mch = motion ? motion->channels() : 0;
  const float* hp = position_.data();
  const float* hn = normal_.data();
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
  // The bulk of the row 8 pixels at a time where the CPU has AVX2 (same results); the
  // scalar loop below does the two edge pixels, the remainder and everything else.
  int vx0 = 0, vx1 = 0;
  if (r.has_history && pc_ch == 3 && nc_ch == 3 && w > 10 && detail::tap_row_avx2_available()) {
    const std::size_t rb = std::size_t(y) * std::size_t(w);
    const detail::TapRow a{w, h, y, prow, nrow, cinfo, mrow, mch, hp, hn, hinfo, thr2, cs, cs2, relative,
                           r.prev_x.data() + rb, r.prev_y.data() + rb, r.taps.data() + rb, r.inside.data() + rb};
    vx0 = 1;
    vx1 = 1 + (w - 2) / 8 * 8;
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
    const float ncl = cinfo[x];  // squared normal length; NaN: non-finite position or normal
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
      const std::size_t ti = std::size_t(y0 + (k >> 1)) * w + std::size_t(x0 + (k & 1)), t = ti * 3;
      const float npl = hinfo[ti];
      if (npl != npl) continue;  // non-finite history position or normal
      const float* pp = hp + t;
      const float* np = hn + t;
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
  std::swap(position_, next_position_);
  std::swap(normal_, next_normal_);
  std::swap(info_, next_info_);
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
