#pragma once
// Sums of a value plane and a count plane over square windows clipped to the plane,
// added directly (separably: a row pass then a column pass), never as differences of
// running or integral sums: those lose small windows next to a firefly of 1e30 to
// cancellation, or turn them negative.
#include <algorithm>
#include <cstddef>
#include <vector>

#include "util/parallel.h"

namespace mcr {

class WindowSums {
 public:
  WindowSums(int width, int height)
      : w_(width), h_(height), val_(std::size_t(width) * std::size_t(height), 0.0),
        cnt_(val_.size(), 0.0) {}
  void set(int x, int y, double value, double count) {
    val_[index(x, y)] = value;
    cnt_[index(x, y)] = count;
  }
  // Replaces the planes by their window sums of half width r (call once, before reading).
  void sum_windows(int r, int nthreads) {
    box(val_, r, nthreads);
    box(cnt_, r, nthreads);
  }
  double value(int x, int y) const { return val_[index(x, y)]; }
  double count(int x, int y) const { return cnt_[index(x, y)]; }
  double mean(int x, int y) const {
    const double c = cnt_[index(x, y)];
    return c > 0 ? val_[index(x, y)] / c : 0.0;
  }

 private:
  std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(w_) + std::size_t(x); }
  void box(std::vector<double>& p, int r, int nthreads) const {
    std::vector<double> tmp(p.size());
    parallel_rows(0, h_, nthreads, [&](int y) {
      for (int x = 0; x < w_; ++x) {
        double s = 0;
        for (int k = std::max(0, x - r), e = std::min(w_ - 1, x + r); k <= e; ++k) s += p[index(k, y)];
        tmp[index(x, y)] = s;
      }
    });
    parallel_rows(0, h_, nthreads, [&](int y) {
      for (int x = 0; x < w_; ++x) {
        double s = 0;
        for (int k = std::max(0, y - r), e = std::min(h_ - 1, y + r); k <= e; ++k) s += tmp[index(x, k)];
        p[index(x, y)] = s;
      }
    });
  }
  int w_, h_;
  std::vector<double> val_, cnt_;
};

}  // namespace mcr
