#pragma once
// The guided filter's window work (guided_sums.cpp): the blocked running box sums in
// double with exact restarts, the per-lane LDL^T solve of each window's coefficients,
// the running sums of those coefficients and the output, in row bands of the roi.
// guided.cpp makes the frame-wide pass that fills the Ctx.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace mcr::guided {

// Per-pixel data the kernels read.
constexpr int kMaxD = 8;
constexpr std::uint8_t kGuideOk = 1;   // every guide channel finite
constexpr std::uint8_t kColourOk = 2;  // every colour channel finite
constexpr std::uint8_t kStat = kGuideOk | kColourOk;  // pixel enters the window statistics

struct Channel {
  const float* data = nullptr;
  int stride = 1, offset = 0;
  double mean = 0, inv_scale = 1;
};

struct Ctx {
  int w = 0, h = 0, r = 0;
  double eps = 0;
  double threshold = 0;  // |colour| >= threshold: outlier sums
  const float* colour = nullptr;  // RGB, interleaved
  const std::uint8_t* flags = nullptr;
  std::array<Channel, kMaxD> ch;
};

// The guide channels as local arrays (kept in registers: the compiler cannot
// assume stores into byte or double rows leave the Ctx alone).
template <int D>
struct GuideView {
  const float* data[D];
  std::size_t stride[D];
  double mean[D], inv[D];
  explicit GuideView(const Ctx& c) {
    for (int j = 0; j < D; ++j) {
      const Channel& g = c.ch[std::size_t(j)];
      data[j] = g.data + g.offset;
      stride[j] = std::size_t(g.stride);
      mean[j] = g.mean;
      inv[j] = g.inv_scale;
    }
  }
  float raw(std::size_t i, int j) const { return data[j][i * stride[j]]; }
  double z(std::size_t i, int j) const { return (double(raw(i, j)) - mean[j]) * inv[j]; }
};

// Filters the roi of `out` in bands of band_h rows (each band's buffers in work[band],
// kept between calls): D guide channels; `outliers`: colour values at or above
// c.threshold go into sums of their own; `mean_colours`: some output pixel has no finite
// guide (it gets its windows' mean colours). Built for the guide sizes run() uses.
template <int D>
void run_bands(const Ctx& c, bool outliers, bool mean_colours, const Roi& roi, Image& out, int nthreads, int band_h,
               std::vector<std::vector<double>>& work);

}  // namespace mcr::guided
