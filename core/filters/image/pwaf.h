#pragma once
// Point-wise adaptive filter (Guo & Pan 2012, "Point-wise Adaptive Filtering for Fast Monte
// Carlo Noise Reduction"): a cross-bilateral filter, eq. 1, with the weight of eq. 8
//   w(p,q) = Gp * Gc * Gn * Gsp * Gsn, each exp(-d^2 / (2 sigma^2)):
//   Gp   d = |p - q| in pixels, sigma_p
//   Gc   d^2 = mean over R,G,B of (I(q) - I~(p))^2, where I~(p) is the estimated range value of
//        3.3 (a fixed Gaussian, prefilter_sigma, of the outlier-suppressed colour) and
//        sigma_c(p)^2 = sigma_c^2 * v(p) + (1e-3 Y(I~(p)))^2 + 1e-300, v(p) the pixel's colour
//        variance: the colour scale adapts to the local noise level
//   Gn   first-hit normals, sigma_n (normal units)
//   Gsp  second-hit positions, sigma_sp in units of the frame's median distance between
//        adjacent pixels of that pass; FALLBACK: the first-hit position pass (still tells
//        surfaces apart at depth edges), with a note
//   Gsn  second-hit normals, sigma_sn; no fallback: dropped (factor 1) with a note, because the
//        first-hit normal is already in Gn and using it again would only sharpen Gn
// Window (3.2): radius linear in the relative variance rho(p) = v(p) / (Y(I~(p))^2 + 0.01)
// (the pixel's expected relMSE if left unfiltered), min_radius at rho = 0, max_radius at
// rho >= variance_max * median over the frame of rho; adaptive=false: max_radius everywhere.
// Outliers (3.3): replaced by their neighbourhood mean before anything else (rule below).
// Variance: the variance pass when present (divided by albedo^2 under demodulate=true);
// otherwise estimated from high-pass residuals (estimate_variance below), per sample and
// divided by the sample count when a sample_count pass exists.
//
// Stages, in the paper's Table 2 order (timings in PwafStats):
//  SS  size selection: outlier replacement, variance (pass or estimate), radius per pixel
//  OS  the estimated range value (the fixed Gaussian)
//  FF  the feature-preserving filter itself (kernels/pwaf_window.h: 8 pixels at a time in
//      float, weights relative to each window's largest; about 5x the scalar double loop)
// With adaptive=true SS and OS cover the whole frame (the median needs it), so tiles agree;
// the filter itself only runs inside the roi.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "filters/filter.h"

namespace mcr {

// What the last execute() did, for benchmarks (Table 2 shape) and --verbose tools.
struct PwafStats {
  double ss_ms = 0, os_ms = 0, ff_ms = 0;  // wall time per stage
  double mean_radius = 0;                  // over the roi
  std::size_t outliers_replaced = 0;       // bright outliers replaced in the roi's support
  std::size_t nonfinite_replaced = 0;      // non-finite colour pixels replaced there
  bool variance_from_pass = false;
  double median_rel_variance = 0;          // the frame's median v/(Y^2+0.01) (adaptive only)
};

class PwafFilter : public Filter {
 public:
  PwafFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  double band_work_bytes() const override { return 200; }
  double statistics_bytes() const override { return 12; }  // its spacings and relative variances (three floats)
  const PwafStats& stats() const { return stats_; }

 protected:
  void check_params() override;
  int own_reach() const override;
  void measure_band(const Frame& band, const Image& colour, const Roi& rows, int nthreads) override;
  void fix_statistics() override;
  void drop_own_statistics() override;
  std::vector<std::string> own_unused() const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  void drop_measured();
  PwafStats stats_;
  // Tiled runs: the frame's median adjacent position distance and median relative variance
  // (measured band by band, then fixed).
  std::vector<float> measured_spacing_, measured_rho_;
  double fixed_spacing_ = 0, fixed_rho_median_ = 0;
};

// The building blocks, public so the tests can check each rule on its own.
namespace pwaf {

// 3.2: radius = min_r + round(t * (max_r - min_r)), t = clamp(rel_variance / rho_max, 0, 1).
// The filter passes rho_max = variance_max * (the frame's median rel_variance). rho_max <= 0
// (a noise-free frame) gives min_r for rel_variance 0 and max_r above. A non-finite or
// negative rel_variance gives max_r (unknown noise: be safe).
int window_radius(double rel_variance, double rho_max, int min_r, int max_r);

// The relative variance that drives the radius: v / (Y^2 + 0.01), with Y the luminance of the
// estimated range value. The 0.01 is the relMSE metric's: rho is the pixel's expected
// contribution to relMSE if it were left unfiltered.
double relative_variance(double variance, double luminance);

}  // namespace pwaf

}  // namespace mcr
