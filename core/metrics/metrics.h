#pragma once
// Image error metrics: how far a denoised (or noisy) render is from its reference.
//
// Common rules for every function here:
// - Only the first three channels (R, G, B) are compared; both images need at least three
//   (Errc::InvalidArgument otherwise) and the same width and height (Errc::SizeMismatch, the
//   message names both sizes). Extra channels (alpha, ...) are ignored, and the two images may
//   have different channel counts. Empty images are rejected (Errc::InvalidArgument).
// - Non-finite values (NaN, +Inf, -Inf) in either image are read as 0 before anything else,
//   so one firefly or NaN pixel gives a large but finite error instead of poisoning the mean.
// - Deterministic: the same inputs give bitwise the same result for any thread count. Rows are
//   reduced in parallel into per-row double sums, which are then added serially in row order.
// - nthreads: worker threads to use; 0 (or negative) means all cores.
#include "image/image.h"

namespace mcr {

// relMSE's denominator term, (x - r)^2 / (r^2 + 0.01): what keeps black pixels' error finite.
constexpr double kRelMseEps = 0.01;

struct ImageMetrics {
  double rmse = 0.0;    // root mean squared error
  double relmse = 0.0;  // relative MSE, (x-r)^2 / (r^2 + 0.01)
  double psnr = 0.0;    // dB on [0,1]-clamped values; +infinity for identical clamped images
  double ssim = 0.0;    // structural similarity on [0,1]-clamped values, 1 = identical
};

// All four metrics of `image` against `reference` in one call.
ImageMetrics compare_images(const Image& reference, const Image& image, int nthreads = 0);

// sqrt(mean over pixels and RGB channels of (x - r)^2). Values are not clamped.
double rmse(const Image& reference, const Image& image, int nthreads = 0);

// Mean over pixels and RGB channels of (x - r)^2 / (r^2 + 0.01). Values are not clamped.
double relmse(const Image& reference, const Image& image, int nthreads = 0);

// 10 * log10(1 / MSE) with both images clamped to [0,1] (peak 1); +infinity when MSE is 0.
double psnr(const Image& reference, const Image& image, int nthreads = 0);

// Mean SSIM (Wang et al. 2004) over all pixels, then over R, G, B, on values clamped to [0,1]:
// separable 11-tap Gaussian window (sigma 1.5, weights summing to 1), borders mirrored without
// repeating the edge pixel (reflect-101: ... c b | a b c ..., reflecting again and again for
// images narrower than the window; a 1-pixel dimension uses that pixel for every tap),
// C1 = 0.01^2, C2 = 0.03^2, local variances as E[x^2] - mu^2 and covariance as E[xy] - mu_x mu_y.
// Symmetric in its arguments; exactly 1 for identical images.
double ssim(const Image& reference, const Image& image, int nthreads = 0);

// The alpha's (coverage's) error: mean over pixels of (a - r)^2 on the first channel of each
// (Cycles' A; not clamped). Needs one channel or more in each, the same size (as above).
double alpha_mse(const Image& reference_alpha, const Image& image_alpha);

// Temporal instability between consecutive frames: mean over pixels of
// |Y(current) - Y(previous)| with luminance Y = 0.2126 R + 0.7152 G + 0.0722 B (as in SVGF and
// BMFR). Values are not clamped.
double temporal_error(const Image& previous, const Image& current, int nthreads = 0);

}  // namespace mcr
