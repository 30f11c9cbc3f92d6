// Pixel-wise metrics (RMSE, relMSE, PSNR), temporal error and compare_images. SSIM: ssim.cpp.
#include "metrics/metrics.h"

#include <cmath>
#include <limits>
#include <vector>

#include "image/luminance.h"
#include "metrics/metrics_internal.h"

namespace mcr {

using metrics_detail::check_pair;
using metrics_detail::clamp01;
using metrics_detail::finite_or_zero;
using metrics_detail::ordered_sum;
using metrics_detail::parallel_blocks;

namespace {

constexpr int kRowsPerBlock = 8;

// Sums over all pixels and RGB channels, each reduced per row and then in row order.
struct ErrorSums {
  double squared = 0.0;          // (x - r)^2
  double relative = 0.0;         // (x - r)^2 / (r^2 + 0.01)
  double squared_clamped = 0.0;  // (clamp(x) - clamp(r))^2
  double count = 0.0;            // number of terms: pixels * 3
};

// Each row is summed in a fixed order (kLanes interleaved partial sums, then added lane by lane),
// so a row's sums do not depend on the thread that computes them.
constexpr int kLanes = 4;

ErrorSums error_sums(const Image& ref, const Image& img, int nthreads) {
  const int w = ref.width(), h = ref.height();
  const int n = 3 * w;  // RGB values per row
  std::vector<double> sq(h), rel(h), sqc(h);
  parallel_blocks(h, kRowsPerBlock, nthreads, [&](int y0, int y1) {
    std::vector<double> a(n), b(n);
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < w; ++x) {
        const float* pr = ref.pixel(x, y);
        const float* pi = img.pixel(x, y);
        for (int c = 0; c < 3; ++c) {
          a[3 * x + c] = finite_or_zero(pr[c]);
          b[3 * x + c] = finite_or_zero(pi[c]);
        }
      }
      double s[kLanes] = {}, r[kLanes] = {}, sc[kLanes] = {};
      const int full = n - n % kLanes;
      for (int i = 0; i < full; i += kLanes) {
        for (int k = 0; k < kLanes; ++k) {
          const double ai = a[i + k], bi = b[i + k];
          const double d = bi - ai, dc = clamp01(bi) - clamp01(ai);
          s[k] += d * d;
          r[k] += d * d / (ai * ai + kRelMseEps);
          sc[k] += dc * dc;
        }
      }
      for (int i = full; i < n; ++i) {
        const int k = i - full;
        const double ai = a[i], bi = b[i];
        const double d = bi - ai, dc = clamp01(bi) - clamp01(ai);
        s[k] += d * d;
        r[k] += d * d / (ai * ai + kRelMseEps);
        sc[k] += dc * dc;
      }
      sq[y] = (s[0] + s[1]) + (s[2] + s[3]);
      rel[y] = (r[0] + r[1]) + (r[2] + r[3]);
      sqc[y] = (sc[0] + sc[1]) + (sc[2] + sc[3]);
    }
  });
  ErrorSums out;
  out.squared = ordered_sum(sq);
  out.relative = ordered_sum(rel);
  out.squared_clamped = ordered_sum(sqc);
  out.count = 3.0 * double(ref.pixel_count());
  return out;
}

double rmse_of(const ErrorSums& s) { return std::sqrt(s.squared / s.count); }
double relmse_of(const ErrorSums& s) { return s.relative / s.count; }
double psnr_of(const ErrorSums& s) {
  const double mse = s.squared_clamped / s.count;
  if (mse == 0.0) return std::numeric_limits<double>::infinity();
  return -10.0 * std::log10(mse);
}

}  // namespace

ImageMetrics compare_images(const Image& reference, const Image& image, int nthreads) {
  check_pair(reference, image, "compare_images", "reference", "image");
  const ErrorSums s = error_sums(reference, image, nthreads);
  ImageMetrics m;
  m.rmse = rmse_of(s);
  m.relmse = relmse_of(s);
  m.psnr = psnr_of(s);
  m.ssim = metrics_detail::ssim_checked(reference, image, nthreads);
  return m;
}

double rmse(const Image& reference, const Image& image, int nthreads) {
  check_pair(reference, image, "rmse", "reference", "image");
  return rmse_of(error_sums(reference, image, nthreads));
}

double relmse(const Image& reference, const Image& image, int nthreads) {
  check_pair(reference, image, "relmse", "reference", "image");
  return relmse_of(error_sums(reference, image, nthreads));
}

double psnr(const Image& reference, const Image& image, int nthreads) {
  check_pair(reference, image, "psnr", "reference", "image");
  return psnr_of(error_sums(reference, image, nthreads));
}

double alpha_mse(const Image& reference_alpha, const Image& image_alpha) {
  const Image &r = reference_alpha, &a = image_alpha;
  if (r.width() != a.width() || r.height() != a.height())
    throw Error(Errc::SizeMismatch, "alpha_mse: reference is " + std::to_string(r.width()) + "x" +
                                        std::to_string(r.height()) + " but image is " + std::to_string(a.width()) + "x" +
                                        std::to_string(a.height()));
  if (r.empty() || a.empty() || r.channels() < 1 || a.channels() < 1)
    throw Error(Errc::InvalidArgument, "alpha_mse: empty image");
  double sum = 0.0;
  for (std::size_t i = 0, n = r.pixel_count(); i < n; ++i) {
    const double d = finite_or_zero(a.data()[i * std::size_t(a.channels())]) -
                     finite_or_zero(r.data()[i * std::size_t(r.channels())]);
    sum += d * d;
  }
  return sum / double(r.pixel_count());
}

double ssim(const Image& reference, const Image& image, int nthreads) {
  check_pair(reference, image, "ssim", "reference", "image");
  return metrics_detail::ssim_checked(reference, image, nthreads);
}

double temporal_error(const Image& previous, const Image& current, int nthreads) {
  check_pair(previous, current, "temporal_error", "previous frame", "current frame");
  const int w = previous.width(), h = previous.height();
  // Non-finite channels count as 0, as in every metric.
  auto luminance = [](const float* p) {
    const float q[3] = {float(finite_or_zero(p[0])), float(finite_or_zero(p[1])), float(finite_or_zero(p[2]))};
    return mcr::luminance(q);
  };
  std::vector<double> rows(h);
  parallel_blocks(h, kRowsPerBlock, nthreads, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      double s = 0.0;
      for (int x = 0; x < w; ++x)
        s += std::abs(luminance(current.pixel(x, y)) - luminance(previous.pixel(x, y)));
      rows[y] = s;
    }
  });
  return ordered_sum(rows) / double(previous.pixel_count());
}

}  // namespace mcr
