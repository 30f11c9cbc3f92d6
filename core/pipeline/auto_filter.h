#pragma once
// Filter `auto`: the right filter for each render, never worse than the input.
//
//  1. Inspect: every image filter whose passes the frame has is a candidate (with its
//     defaults: each already skips constant or absent feature passes and steps back
//     toward the input where it is not estimated to help, prepare/step_back.h).
//  2. Score on a sample: tiles spread over the region (about sample_fraction of its
//     pixels, each cropped with a margin so the filters see their neighbourhood), every
//     channel weighted as relMSE weighs it, the noise from kernels/noise_scale.h.
//     - With a variance pass: Stein's unbiased risk estimate, the divergence by a Monte
//       Carlo probe (Ramani et al. 2008: a second run on the input plus eps times random
//       signs).
//     - Without (the noise then the image's own estimate, and Monte Carlo's noise skewed,
//       not Gaussian; a region under 8x8 by SURE on that estimate): held-out pixels (one in
//       five, replaced by their neighbours' mean in the second run, after Batson & Royer
//       2019), each candidate scored by
//       (f - y)^2 - e + 2 (f - f_J)(y - y_J): SURE's E n f taken from the pixel's own
//       excursion and the filter's response to it instead of a derivative; e, the input's
//       error there, its noise variance (at most 16x its 3x3 range squared) or a far-out
//       pixel's squared distance to its median (.cpp).
//     Besides each filter, the mean of every two (pairs): scored from their two runs, with no
//     run of its own (every score is linear in the result; .cpp).
//  3. Run the best (one filter, or two and their mean) on the whole region, or copy the input when its own estimated relMSE
//     is below `converged` (held out, without far-out pixels where they are under 1 in
//     1000: a converged render's rare glints) or the best is not estimated to cut it by min_gain: with a
//     variance pass by its SURE score, without by a blind-spot check, its result at the
//     held-out pixels made from their neighbours alone (errs toward keeping a clean
//     render's detail).
// What it chose, every score and what each stage skipped go to the notes (`--verbose`,
// the plugin's and Python's notes).
#include <string>
#include <vector>

#include "filters/filter.h"

namespace mcr {

struct AutoScore {
  std::string filter;       // "input" for the input itself, "a+b" for the mean of filters a and b
  double relmse = 0;        // estimated relMSE on the sample
  double seconds = 0;       // time of its two runs on the sample (a mean: both filters')
};

// The blind-spot check of the best-scored filter (run only without a variance pass).
struct AutoCheck {
  std::string filter;       // empty when it did not run
  double relmse = 0;        // the filter's estimated relMSE at the held-out pixels
  double input = 0;         // the input's there
};

// A kept input's firefly clamp (kept_firefly_k): the firefly step's rule at a k four times its 8,
// the smallest power of two that left the tune scenes' references (room, glossy, jewel) as they
// are (16 cut one pixel of jewel's), over the step's 7x7 window.
constexpr double kKeptFireflyK = 32.0;
constexpr int kKeptFireflyRadius = 3;
constexpr double kKeptFireflyFloor = 0.1;  // a clamp smaller than this (x the exposure step) is undone

class AutoFilter : public Filter {
 public:
  AutoFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  // The scores of the last execute(), best first (empty when nothing was scored).
  const std::vector<AutoScore>& scores() const { return scores_; }
  // The filter the last execute() ran ("input" when it copied the input; "a+b" for the mean of
  // filters a and b, as its score is named).
  const std::string& chosen() const { return chosen_; }
  // The blind-spot check of the last execute() (filter empty when it did not run).
  const AutoCheck& check() const { return check_; }

 protected:
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  void clamp_kept_fireflies(const Frame& frame, const Roi& roi, int nthreads, Image& out);
  std::vector<AutoScore> scores_;
  std::string chosen_;
  AutoCheck check_;
};

}  // namespace mcr
