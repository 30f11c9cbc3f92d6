#pragma once
// Guided image filter (He, Sun & Tang 2013, Algorithm 1) with a multi-channel
// guide built from feature passes, as Bauszat et al. 2011 use it for path traced
// images (guide = 3 normal channels + depth) and as the BMFR paper (Koskela et al.
// 2019, section 7) extends it to any number of feature buffers.
//
// Per output colour channel c and every window w_k (the (2r+1)^2 square around
// pixel k, clipped at the image border, holding only the valid pixels):
//   a_k = (Sigma_k + eps I)^-1 cov_k(z, p_c)   Sigma_k: d x d covariance of the guide z
//   b_k = mean_k(p_c) - a_k . mean_k(z)
// i.e. the ridge regression min sum_{i in w_k} [(a.z_i + b - p_i)^2 + eps |a|^2] of
// He et al.'s eq. 3 (eps per pixel, so n_k eps |a|^2 for n_k valid pixels; Sigma and
// cov carry the 1/n_k). The output is the plain average over the
// windows that contain pixel i (centres k inside the image, within r of i, with at
// least one valid pixel): q_i = mean_k (a_k . z_i + b_k).
//
// Guide normalisation (so that one eps fits every guide; epsilon=0 below): every guide channel is
// centred on its mean over the frame, then divided by a scale shared by the channels
// of one pass (normal xyz, position xyz, albedo rgb, colour rgb share theirs):
//   normal, albedo          s = max(1, rms std)  unit quantities keep their own scale
//   depth, position,        s = rms std          metric quantities: unit variance
//   luminance, colour                            (s = 1 when that std is 0)
// where rms std = sqrt(mean over the pass's channels of the variance), mean and
// variance taken over the pixels where every guide channel is finite, over the whole
// frame (not the roi). Since s >= std, every normalised value is bounded by
// sqrt(3 N) for N pixels, which keeps the moment sums well conditioned.
//
// Cost: O(N) for any radius. Box sums are running sums in double over one stacked
// image (count, d means, d(d+1)/2 second moments, 3 colour means, 3d cross moments),
// vertical then horizontal; the coefficients (3d slopes, 3 offsets, the count, and
// the window mean colours when some pixel has no finite guide) go through the same
// running sums a second time. The work is cut into row bands whose height depends
// on the radius and the roi only (max(256, min(16r, roi height / 2)) rows), never on
// the thread count, so every thread count gives the same bits; each band recomputes
// r coefficient rows past each of its ends.
//
// Running sums forget rounding error only where they restart, so a pixel far
// brighter than the rest of the frame (a firefly of 1e30 among values near 1) would
// otherwise leave its rounding error behind in every later window: colour values at
// or above 2^20 times the power of two just above the 90th percentile of the nonzero
// |colour| go into their own set of sums (and the coefficients of the windows holding
// them into their own coefficient sums). Every set of sums has its own count and
// restarts at exactly 0 when that count is 0, so pixels farther than 2r from an
// outlier never see it, and a pixel with no valid pixel nearby sees nothing.
// The d x d systems (Sigma + eps I) are solved by an LDL^T factorisation with the
// pivots floored at eps (exact arithmetic never gives a smaller one; the floor
// catches rounding and NaN). Per-pixel work runs on GCC vectors of doubles.
#include <cstddef>
#include <vector>

#include "filters/filter.h"

namespace mcr {

namespace guided {
// epsilon=0 (the default): epsilon = scale x the frame's median relative noise variance,
// clamped to [1e-8, 1e6] (1e6 when not finite): a noisy frame is smoothed hard, a clean one
// barely. The noise is kernels/noise_scale.h's, taken on the colour the filter gets (after
// demodulation), medians over the finite pixels (0 when none):
//   relative  the median of `relative` (high-pass residual energy over median
//             luminance^2, robust to sparse bright structure);
//   level     sqrt(median of robust() / relative): the colour level that noise is relative to.
// A colour guide (colour, luminance, normal_depth_colour) is then divided by
// max(rms std, level) instead of its rms std: its noise variance in guide units is at most
// about the relative one, so epsilon is `scale` noise variances for it too, and a flat
// noisy frame (std = noise) is smoothed instead of taken as structure.
struct FrameNoise {
  double relative = 0, level = 0;
};
FrameNoise frame_noise(const Image& colour, int nthreads);
// The values frame_noise() takes the medians of, for `rows` (appended), and their medians
// (reordering them): a tiled run gathers them band by band.
// Kept as floats (a frame's worth is what a tiled run holds between passes).
void gather_frame_noise(const Image& colour, const Roi& rows, int nthreads, std::vector<float>& relative,
                        std::vector<float>& robust);
FrameNoise frame_noise_of(std::vector<float>& relative, std::vector<float>& robust);

// One row's share of the guide statistics (validity count, mean and squared deviations per
// guide channel, exponent histogram of the colour), combined over the rows in order.
constexpr int kMaxGuideChannels = 7;
struct RowStats {
  std::uint64_t n = 0, invalid = 0;
  double mean[kMaxGuideChannels] = {}, m2[kMaxGuideChannels] = {};
  std::uint32_t hist[256] = {};
};
double auto_epsilon(double scale, double median_relative_noise);
// The rows of the row bands the sums run in (guided_sums.cpp): 16r, at least 64, a multiple
// of 64 (each band recomputes r coefficient rows past each end), the same for any roi, on the
// image's grid of that height (a tiled run's bands start on it).
int band_rows(int r);
}  // namespace guided

// What the last execute() did, for tests and --verbose tools.
struct GuidedStats {
  int guide_channels = 0;          // d
  std::vector<double> guide_mean;  // per guide channel, over the frame
  std::vector<double> guide_scale; // per guide channel (shared within a pass)
  double outlier_threshold = 0;    // |colour| at or above it goes to the outlier sums (inf: none)
  std::size_t outlier_pixels = 0;  // in the frame
  std::size_t invalid_pixels = 0;  // non-finite colour or guide, in the frame
  int bands = 0;                   // row bands the roi was cut into
};

class GuidedFilter : public Filter {
 public:
  GuidedFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  double band_work_bytes() const override { return 192; }
  double statistics_bytes() const override { return 8; }  // the noise values of its first statistics pass (two floats)
  const GuidedStats& stats() const { return stats_; }

  // The passes a guide choice reads ("normal_depth" -> normal, depth); colour-based
  // guides (luminance, colour) read none. Throws BadParameterValue for unknown names.
  static std::vector<Role> guide_passes(const std::string& guide);

 protected:
  PassNeeds own_needs() const override;
  std::vector<std::string> own_unused() const override;
  // A band's sums start on the grid line above its first row (up to band_rows - 1 rows up).
  int own_reach() const override {
    const int r = int(params_.get_int("radius"));
    return 2 * r + 1 + guided::band_rows(r);
  }
  int band_alignment() const override { return guided::band_rows(int(params_.get_int("radius"))); }
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  void measure_band(const Frame& band, const Image& colour, const Roi& rows, int nthreads) override;
  bool statistics_pass_done() override;
  void drop_own_statistics() override;
  bool noise_from_image() const { return params_.get_float("epsilon") == 0.0; }

  GuidedStats stats_;
  std::vector<std::vector<double>> work_;  // per row band, kept between calls
  // Tiled runs: the frame's noise (epsilon=0; a first pass) and every row's guide statistics.
  std::vector<float> measured_rel_, measured_abs_;
  guided::FrameNoise fixed_noise_;
  std::vector<guided::RowStats> row_stats_;
};

}  // namespace mcr
