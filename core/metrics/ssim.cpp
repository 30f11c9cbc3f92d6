// SSIM with a separable 11-tap Gaussian window (see metrics.h for the exact definition).
//
// Rows are processed in fixed blocks. Each block keeps a ring of the last 11 horizontally
// filtered rows of the five moment images (x, y, x^2, y^2, xy) and filters them vertically into
// one row of SSIM values, whose sum is stored per row. A row's value does not depend on the
// block it falls in, and the row sums are added in row order, so the result is the same for any
// thread count.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "metrics/metrics_internal.h"

namespace mcr::metrics_detail {

namespace {

constexpr int kRadius = 5;
constexpr int kTaps = 2 * kRadius + 1;
constexpr int kMoments = 5;  // x, y, x^2, y^2, xy
constexpr int kRowsPerBlock = 64;  // 10 halo rows per block are filtered twice
constexpr double kSigma = 1.5;
constexpr double kC1 = 0.01 * 0.01;  // (K1 L)^2, L = 1
constexpr double kC2 = 0.03 * 0.03;  // (K2 L)^2

std::array<double, kTaps> gaussian_window() {
  std::array<double, kTaps> g{};
  double sum = 0.0;
  for (int i = 0; i < kTaps; ++i) {
    const double d = i - kRadius;
    g[i] = std::exp(-d * d / (2.0 * kSigma * kSigma));
    sum += g[i];
  }
  for (double& v : g) v /= sum;
  return g;
}

// Reflect-101 (... c b | a b c | b a ...), repeated for indices more than one period away.
int reflect101(int i, int n) {
  if (n == 1) return 0;
  const int period = 2 * (n - 1);
  i %= period;
  if (i < 0) i += period;
  return i < n ? i : period - i;
}

// The two convolutions below use the symmetry of the window (g[t] == g[10 - t]) and work on
// chunks of kLanes outputs whose partial sums stay in registers. Every output is summed in the
// same order whatever chunk it falls in.
constexpr int kLanes = 8;

// out[x] = sum_t g[t] * in[x + t], for x in [0, n); `in` holds n + 2*kRadius values.
void convolve_row(const double* __restrict in, double* __restrict out, int n,
                  const std::array<double, kTaps>& g) {
  int x = 0;
  for (; x + kLanes <= n; x += kLanes) {
    double s[kLanes];
    for (int k = 0; k < kLanes; ++k) s[k] = g[kRadius] * in[x + kRadius + k];
    for (int t = 0; t < kRadius; ++t)
      for (int k = 0; k < kLanes; ++k) s[k] += g[t] * (in[x + t + k] + in[x + kTaps - 1 - t + k]);
    for (int k = 0; k < kLanes; ++k) out[x + k] = s[k];
  }
  for (; x < n; ++x) {
    double s = g[kRadius] * in[x + kRadius];
    for (int t = 0; t < kRadius; ++t) s += g[t] * (in[x + t] + in[x + kTaps - 1 - t]);
    out[x] = s;
  }
}

// out[x] = sum_t g[t] * rows[t][x], for x in [0, n).
void convolve_column(const double* const* rows, double* __restrict out, int n,
                     const std::array<double, kTaps>& g) {
  int x = 0;
  for (; x + kLanes <= n; x += kLanes) {
    double s[kLanes];
    for (int k = 0; k < kLanes; ++k) s[k] = g[kRadius] * rows[kRadius][x + k];
    for (int t = 0; t < kRadius; ++t)
      for (int k = 0; k < kLanes; ++k) s[k] += g[t] * (rows[t][x + k] + rows[kTaps - 1 - t][x + k]);
    for (int k = 0; k < kLanes; ++k) out[x + k] = s[k];
  }
  for (; x < n; ++x) {
    double s = g[kRadius] * rows[kRadius][x];
    for (int t = 0; t < kRadius; ++t) s += g[t] * (rows[t][x] + rows[kTaps - 1 - t][x]);
    out[x] = s;
  }
}

class SsimBlock {
 public:
  SsimBlock(const Image& ref, const Image& img, const std::array<double, kTaps>& g,
            const std::vector<int>& xmap)
      : ref_(ref), img_(img), g_(g), xmap_(xmap), w_(ref.width()), h_(ref.height()),
        padded_(std::size_t(kMoments) * (w_ + 2 * kRadius)),
        ring_(std::size_t(kTaps) * kMoments * w_),
        acc_(std::size_t(kMoments + 1) * w_) {}

  // Sum of the SSIM map over row y of channel c, for y in [y0, y1), into row_sums[y].
  void run(int c, int y0, int y1, double* row_sums) {
    for (int v = y0 - kRadius; v < y0 + kRadius; ++v) filter_row(c, v);
    for (int y = y0; y < y1; ++y) {
      filter_row(c, y + kRadius);
      row_sums[y] = ssim_row(y);
    }
  }

 private:
  static int slot(int v) { return ((v % kTaps) + kTaps) % kTaps; }
  double* ring_row(int v, int m) {
    return ring_.data() + (std::size_t(slot(v)) * kMoments + m) * w_;
  }

  // Horizontally filtered moments of virtual row v (reflected into the image) into the ring.
  void filter_row(int c, int v) {
    const int y = reflect101(v, h_);
    const int pw = w_ + 2 * kRadius;
    double* px = padded_.data();
    double* py = px + pw;
    double* pxx = py + pw;
    double* pyy = pxx + pw;
    double* pxy = pyy + pw;
    for (int j = 0; j < pw; ++j) {
      const int x = xmap_[j];
      const double a = clamp01(finite_or_zero(ref_.at(x, y, c)));
      const double b = clamp01(finite_or_zero(img_.at(x, y, c)));
      px[j] = a;
      py[j] = b;
      pxx[j] = a * a;
      pyy[j] = b * b;
      pxy[j] = a * b;
    }
    for (int m = 0; m < kMoments; ++m)
      convolve_row(px + std::size_t(m) * pw, ring_row(v, m), w_, g_);
  }

  double ssim_row(int y) {
    for (int m = 0; m < kMoments; ++m) {
      const double* rows[kTaps];
      for (int t = 0; t < kTaps; ++t) rows[t] = ring_row(y - kRadius + t, m);
      convolve_column(rows, acc_.data() + std::size_t(m) * w_, w_, g_);
    }
    const double* mx = acc_.data();
    const double* my = mx + w_;
    const double* exx = my + w_;
    const double* eyy = exx + w_;
    const double* exy = eyy + w_;
    double* map = acc_.data() + std::size_t(kMoments) * w_;
    for (int x = 0; x < w_; ++x) {
      const double sxx = exx[x] - mx[x] * mx[x];
      const double syy = eyy[x] - my[x] * my[x];
      const double sxy = exy[x] - mx[x] * my[x];
      const double num = (2.0 * mx[x] * my[x] + kC1) * (2.0 * sxy + kC2);
      const double den = (mx[x] * mx[x] + my[x] * my[x] + kC1) * (sxx + syy + kC2);
      map[x] = num / den;
    }
    // Fixed order: kLanes interleaved partial sums, then combined pairwise.
    double part[kLanes] = {};
    int x = 0;
    for (; x + kLanes <= w_; x += kLanes)
      for (int k = 0; k < kLanes; ++k) part[k] += map[x + k];
    for (int k = 0; x < w_; ++x, ++k) part[k] += map[x];
    for (int width = kLanes / 2; width > 0; width /= 2)
      for (int k = 0; k < width; ++k) part[k] += part[k + width];
    return part[0];
  }

  const Image& ref_;
  const Image& img_;
  const std::array<double, kTaps>& g_;
  const std::vector<int>& xmap_;
  int w_, h_;
  std::vector<double> padded_;  // kMoments padded source rows
  std::vector<double> ring_;    // kTaps x kMoments horizontally filtered rows
  std::vector<double> acc_;     // kMoments vertically filtered rows, then the SSIM map row
};

}  // namespace

double ssim_checked(const Image& reference, const Image& image, int nthreads) {
  const int w = reference.width(), h = reference.height();
  const std::array<double, kTaps> g = gaussian_window();
  std::vector<int> xmap(std::size_t(w) + 2 * kRadius);
  for (int j = 0; j < int(xmap.size()); ++j) xmap[j] = reflect101(j - kRadius, w);

  std::vector<double> row_sums(std::size_t(3) * h);
  parallel_blocks(h, kRowsPerBlock, nthreads, [&](int y0, int y1) {
    SsimBlock block(reference, image, g, xmap);
    for (int c = 0; c < 3; ++c) block.run(c, y0, y1, row_sums.data() + std::size_t(c) * h);
  });

  const double n = double(reference.pixel_count());
  double total = 0.0;
  for (int c = 0; c < 3; ++c) {
    double s = 0.0;
    for (int y = 0; y < h; ++y) s += row_sums[std::size_t(c) * h + y];
    total += s / n;
  }
  return total / 3.0;
}

}  // namespace mcr::metrics_detail
