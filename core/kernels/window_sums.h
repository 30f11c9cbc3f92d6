#pragma once
// Sums of a value plane (and optionally a count plane) over square windows clipped to the
// plane, added directly (separably: a row pass then a column pass), never as differences
// of running or integral sums: those lose small windows next to a firefly of 1e30 to
// cancellation, or turn them negative. reset() keeps the memory, so a caller that keeps
// one object (thread_local) between frames does not pay for fresh pages each time.
#include <algorithm>
#include <cstddef>
#include <vector>

#include "util/parallel.h"

namespace mcr {

class WindowSums {
 public:
  WindowSums() = default;
  WindowSums(int width, int height, bool counts = true) { reset(width, height, counts); }
  void reset(int width, int height, bool counts = true) {
    w_ = width;
    h_ = height;
    counts_ = counts;
    val_.assign(std::size_t(width) * std::size_t(height), 0.0);
    if (counts) cnt_.assign(val_.size(), 0.0);
  }
  void set(int x, int y, double value, double count = 1.0) {
    val_[index(x, y)] = value;
    if (counts_) cnt_[index(x, y)] = count;
  }
  // Replaces the planes by their window sums of half width r (call once, before reading).
  void sum_windows(int r, int nthreads) {
    box(val_, r, nthreads);
    if (counts_) box(cnt_, r, nthreads);
  }
  double value(int x, int y) const { return val_[index(x, y)]; }
  double count(int x, int y) const { return counts_ ? cnt_[index(x, y)] : 0.0; }
  double mean(int x, int y) const {
    const double c = cnt_[index(x, y)];
    return c > 0 ? val_[index(x, y)] / c : 0.0;
  }

 private:
  std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(w_) + std::size_t(x); }
  void box(std::vector<double>& p, int r, int nthreads) {
    tmp_.resize(p.size());
    parallel_rows(0, h_, nthreads, [&](int y) {
      const double* row = p.data() + index(0, y);
      double* out = tmp_.data() + index(0, y);
      double s = 0;  // a sliding sum would cancel: add each window afresh, r is small
      for (int x = 0; x < w_; ++x) {
        s = 0;
        for (int k = std::max(0, x - r), e = std::min(w_ - 1, x + r); k <= e; ++k) s += row[k];
        out[x] = s;
      }
    });
    parallel_rows(0, h_, nthreads, [&](int y) {
      double* out = p.data() + index(0, y);
      const int y0 = std::max(0, y - r), y1 = std::min(h_ - 1, y + r);
      for (int x = 0; x < w_; ++x) out[x] = 0;
      for (int k = y0; k <= y1; ++k) {
        const double* src = tmp_.data() + index(0, k);
        for (int x = 0; x < w_; ++x) out[x] += src[x];
      }
    });
  }
  int w_ = 0, h_ = 0;
  bool counts_ = true;
  std::vector<double> val_, cnt_, tmp_;
};

}  // namespace mcr
