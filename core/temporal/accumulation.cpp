#include "temporal/accumulation.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

void AccumulationBuffer::reset() {
  value_ = Image();
  next_ = Image();
  count_.clear();
  next_count_.clear();
}

void AccumulationBuffer::begin(const Reprojection& r, const Image& current) {
  const int w = current.width(), h = current.height(), ch = current.channels();
  if (ch > 8) throw Error(Errc::Internal, "accumulation: at most 8 channels");
  usable_ = r.has_history && !r.cut && value_.width() == w && value_.height() == h && value_.channels() == ch &&
            r.width == w && r.height == h && count_.size() == current.pixel_count();
  if (next_.width() != w || next_.height() != h || next_.channels() != ch) next_ = Image(w, h, ch);
  next_count_.resize(current.pixel_count());  // every entry is rewritten by row()
}

namespace {

// Row y of the blend for 3 channels (every BMFR buffer): the generic loop below with the
// channel count fixed, so the history and the blend stay in registers. Same operations in
// the same order.
void row3(int y, const Reprojection& r, const float* crow_all, const float* hist, const float* hcount, float af,
          int w, float* orow, float* ncount) {
  const float* crow = crow_all + std::size_t(y) * std::size_t(w) * 3;
  const std::uint8_t* taps = r.taps.data() + std::size_t(y) * std::size_t(w);
  const float* pxs = r.prev_x.data() + std::size_t(y) * std::size_t(w);
  const float* pys = r.prev_y.data() + std::size_t(y) * std::size_t(w);
  const std::size_t sw = std::size_t(w);
  for (int x = 0; x < w; ++x) {
    const float* c = crow + std::size_t(x) * 3;
    float* o = orow + std::size_t(x) * 3;
    const float c0 = c[0], c1 = c[1], c2 = c[2];
    const bool finite = ((c0 - c0) + (c1 - c1) + (c2 - c2)) == 0.0f;  // x - x is NaN for NaN/Inf
    float h0 = 0, h1 = 0, h2 = 0, n = 0;
    bool have = false;
    const std::uint8_t mask = hist ? taps[x] : 0;
    if (mask) {
      const float px = pxs[x], py = pys[x];
      const int x0 = floor_int(px), y0 = floor_int(py);
      const float fx = px - float(x0), fy = py - float(y0);
      const float wt[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
      const std::size_t t0 = std::size_t(y0) * sw + std::size_t(x0);
      const std::size_t tt[4] = {t0, t0 + 1, t0 + sw, t0 + sw + 1};
      float sum = 0, cnt = 0;
      for (int k = 0; k < 4; ++k) {
        if (!(mask & (1u << k)) || wt[k] <= 0.0f) continue;
        const std::size_t t = tt[k];
        const float tc = hcount[t];
        if (!(tc > 0.0f)) continue;
        sum += wt[k];
        cnt += wt[k] * tc;
        const float* hp = hist + t * 3;
        h0 += wt[k] * hp[0];
        h1 += wt[k] * hp[1];
        h2 += wt[k] * hp[2];
      }
      if (sum > 1e-6f) {
        const float inv = 1.0f / sum;
        h0 *= inv;
        h1 *= inv;
        h2 *= inv;
        n = std::max(1.0f, float(int(cnt * inv + 0.5f)));
        have = true;
      }
    }
    if (!finite) {
      o[0] = have ? h0 : 0.0f;  // invalid without history: value 0, count 0
      o[1] = have ? h1 : 0.0f;
      o[2] = have ? h2 : 0.0f;
      ncount[x] = have ? n : 0.0f;
      continue;
    }
    if (!have) {
      o[0] = c0;
      o[1] = c1;
      o[2] = c2;
      ncount[x] = 1.0f;
      continue;
    }
    const float wn = std::max(1.0f / (n + 1.0f), af);
    o[0] = h0 + wn * (c0 - h0);
    o[1] = h1 + wn * (c1 - h1);
    o[2] = h2 + wn * (c2 - h2);
    ncount[x] = std::min(n + 1.0f, 65535.0f);
  }
}

}  // namespace

void AccumulationBuffer::row(int y, const Reprojection& r, const Image& current, double alpha) {
  const int w = current.width(), h = current.height(), ch = current.channels();
  if (ch == 3) {
    row3(y, r, current.data(), usable_ ? value_.data() : nullptr, usable_ ? count_.data() : nullptr, float(alpha), w,
         next_.data() + std::size_t(y) * std::size_t(w) * 3, next_count_.data() + std::size_t(y) * std::size_t(w));
    return;
  }
  const float* hist = usable_ ? value_.data() : nullptr;
  const float* hcount = usable_ ? count_.data() : nullptr;
  const float af = float(alpha);
  const float* crow = current.data() + std::size_t(y) * w * ch;
  float* orow = next_.data() + std::size_t(y) * w * ch;
  float* ncount = next_count_.data() + std::size_t(y) * w;
  for (int x = 0; x < w; ++x) {
    const std::size_t i = std::size_t(y) * w + x;
    const float* c = crow + std::size_t(x) * ch;
    float* o = orow + std::size_t(x) * ch;
    bool finite = true;
    for (int k = 0; k < ch; ++k) finite = finite && std::isfinite(c[k]);
    float hv[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    float n = 0;
    bool have = false;
    const std::uint8_t mask = hist ? r.taps[i] : 0;
    if (mask) {
      // Bilinear taps that passed the tests and hold a valid history, value and count in
      // one go, normalised by the kept weights only.
      const float px = r.prev_x[i], py = r.prev_y[i];
      const int x0 = floor_int(px), y0 = floor_int(py);
      const float fx0 = float(x0), fy0 = float(y0);
      const float fx = px - fx0, fy = py - fy0;
      const float wt[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
      float sum = 0, cnt = 0;
      for (int k = 0; k < 4; ++k) {
        if (!(mask & (1u << k)) || wt[k] <= 0.0f) continue;
        const std::size_t t = std::size_t(y0 + (k >> 1)) * std::size_t(w) + std::size_t(x0 + (k & 1));
        const float tc = hcount[t];
        if (!(tc > 0.0f)) continue;
        sum += wt[k];
        cnt += wt[k] * tc;
        const float* hp = hist + t * std::size_t(ch);
        for (int k2 = 0; k2 < ch; ++k2) hv[k2] += wt[k] * hp[k2];
      }
      if (sum > 1e-6f) {
        const float inv = 1.0f / sum;
        for (int k2 = 0; k2 < ch; ++k2) hv[k2] *= inv;
        n = std::max(1.0f, float(int(cnt * inv + 0.5f)));  // counts are >= 0: round half up
        have = true;
      }
    }
    if (!finite) {
      if (have) {
        std::copy(hv, hv + ch, o);
        ncount[x] = n;
      } else {  // invalid, value 0, count 0
        std::fill(o, o + ch, 0.0f);
        ncount[x] = 0.0f;
      }
      continue;
    }
    if (!have) {
      std::copy(c, c + ch, o);
      ncount[x] = 1.0f;
      continue;
    }
    const float wn = std::max(1.0f / (n + 1.0f), af);
    for (int k = 0; k < ch; ++k) o[k] = hv[k] + wn * (c[k] - hv[k]);
    ncount[x] = std::min(n + 1.0f, 65535.0f);
  }
  (void)h;
}

void AccumulationBuffer::finish() {
  std::swap(value_, next_);
  std::swap(count_, next_count_);
}

const Image& AccumulationBuffer::accumulate(const Reprojection& r, const Image& current, double alpha, int nthreads) {
  begin(r, current);
  parallel_rows(0, current.height(), nthreads, [&](int y) { row(y, r, current, alpha); });
  finish();
  return value_;
}

void TemporalAccumulator::reset() {
  geometry_.reset();
  buffer_.reset();
  reprojection_ = Reprojection();
}

const Image& TemporalAccumulator::accumulate(const Frame& frame, const Image& colour, int nthreads) {
  const Image& pos = frame.image(Role::Position, Prefer::Geometry);
  const Image& nrm = frame.image(Role::Normal, Prefer::Geometry);
  const Pass* mp = frame.find(Role::Motion);
  return accumulate(colour, pos, nrm, mp ? &mp->image : nullptr, nthreads);
}

const Image& TemporalAccumulator::accumulate(const Frame& frame, const Image& colour,
                                             const std::function<void(int)>& before_row, int nthreads) {
  const Image& pos = frame.image(Role::Position, Prefer::Geometry);
  const Image& nrm = frame.image(Role::Normal, Prefer::Geometry);
  const Pass* mp = frame.find(Role::Motion);
  before_row_ = before_row ? &before_row : nullptr;
  try {
    const Image& out = accumulate(colour, pos, nrm, mp ? &mp->image : nullptr, nthreads);
    before_row_ = nullptr;
    return out;
  } catch (...) {
    before_row_ = nullptr;
    throw;
  }
}

const Image& TemporalAccumulator::accumulate(const Image& colour, const Image& position, const Image& normal,
                                             const Image* motion, int nthreads) {
  if (position.width() != colour.width() || position.height() != colour.height() ||
      normal.width() != colour.width() || normal.height() != colour.height())
    throw Error(Errc::SizeMismatch, "accumulation: colour, position and normal differ in size");
  if (position.channels() < 3 || normal.channels() < 3)
    throw Error(Errc::InvalidArgument, "accumulation: position and normal need 3 channels");
  // Reprojection and accumulation fused: row y is blended right after its taps are
  // decided (it reads only the previous frame's buffers). A camera cut is only known once
  // every row is done; the blend is then redone without history.
  Reprojection& r = reprojection_;
  geometry_.begin(position, normal, motion, r);
  buffer_.begin(r, colour);
  const int h = colour.height();
  row_lost_.assign(std::size_t(std::max(h, 0)), 0);
  parallel_rows(0, h, nthreads, [&](int y) {
    if (before_row_) (*before_row_)(y);
    row_lost_[std::size_t(y)] = geometry_.row(y, position, normal, motion, params_.reprojection, r);
    buffer_.row(y, r, colour, params_.alpha);
  });
  std::size_t lost = 0;
  for (std::size_t v : row_lost_) lost += v;
  if (geometry_.finish(params_.reprojection, r, lost)) {
    buffer_.begin(r, colour);
    parallel_rows(0, h, nthreads, [&](int y) { buffer_.row(y, r, colour, params_.alpha); });
  }
  buffer_.finish();
  return buffer_.value();
}

}  // namespace mcr
