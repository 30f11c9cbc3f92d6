#include "temporal/accumulation.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"
#include "util/parallel.h"

namespace mcr {

void AccumulationBuffer::reset() {
  value_ = Image();
  count_.clear();
}

const Image& AccumulationBuffer::accumulate(const Reprojection& r, const Image& current, double alpha, int nthreads) {
  const int w = current.width(), h = current.height(), ch = current.channels();
  if (ch > 8) throw Error(Errc::Internal, "accumulation: at most 8 channels");
  const bool usable = r.has_history && !r.cut && value_.width() == w && value_.height() == h &&
                      value_.channels() == ch && r.width == w && r.height == h;
  Image next(w, h, ch);
  std::vector<float> next_count(current.pixel_count(), 0.0f);
  const float* hist = usable ? value_.data() : nullptr;
  const float* hcount = usable ? count_.data() : nullptr;
  parallel_rows(0, h, nthreads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      const float* c = current.pixel(x, y);
      float* o = next.pixel(x, y);
      bool finite = true;
      for (int k = 0; k < ch; ++k) finite = finite && std::isfinite(c[k]);
      float hv[8];
      float n = 0;
      bool have = false;
      if (hist) {
        auto valid = [&](std::size_t t) { return hcount[t] > 0.0f; };
        if (r.sample(i, hist, ch, r.taps[i], hv, valid) > 0.0f) {
          float cnt = 0;
          r.sample(i, hcount, 1, r.taps[i], &cnt, valid);
          n = std::max(1.0f, std::round(cnt));
          have = true;
        }
      }
      if (!finite) {
        if (have) {
          std::copy(hv, hv + ch, o);
          next_count[i] = n;
        }  // else: invalid, value 0, count 0
        continue;
      }
      if (!have) {
        std::copy(c, c + ch, o);
        next_count[i] = 1.0f;
        continue;
      }
      const double wn = std::max(1.0 / (double(n) + 1.0), alpha);
      for (int k = 0; k < ch; ++k) o[k] = float((1.0 - wn) * hv[k] + wn * c[k]);
      next_count[i] = std::min(n + 1.0f, 65535.0f);
    }
  });
  value_ = std::move(next);
  count_ = std::move(next_count);
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

const Image& TemporalAccumulator::accumulate(const Image& colour, const Image& position, const Image& normal,
                                             const Image* motion, int nthreads) {
  if (position.width() != colour.width() || position.height() != colour.height() ||
      normal.width() != colour.width() || normal.height() != colour.height())
    throw Error(Errc::SizeMismatch, "accumulation: colour, position and normal differ in size");
  if (position.channels() < 3 || normal.channels() < 3)
    throw Error(Errc::InvalidArgument, "accumulation: position and normal need 3 channels");
  reprojection_ = geometry_.update(position, normal, motion, params_.reprojection, nthreads);
  return buffer_.accumulate(reprojection_, colour, params_.alpha, nthreads);
}

}  // namespace mcr
