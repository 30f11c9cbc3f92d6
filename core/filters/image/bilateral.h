#pragma once
#include "kernels/cross_bilateral.h"
#include "filters/filter.h"

namespace mcr {

// Cross-bilateral filter (Immonen 2017, 3.4 and 5.3): for every pixel p
//   out(p) = sum_q w(p,q) c(q) / sum_q w(p,q),
//   w(p,q) = exp(-|q-p|^2 / (2 spatial_sigma^2)) * prod_f exp(-|f(p)-f(q)|^2 / (2 f_sigma^2))
// over the square window |q-p| <= radius (clipped and renormalised at the borders),
// f in {colour, normal, position, albedo, depth}, each switched by use_<f>.
// order=1 replaces the weighted mean by a weighted first-order regression on the
// features over the same window (filters/feature_regression.h), with the colour
// weight taken on the order-0 result.
class BilateralFilter : public Filter {
 public:
  BilateralFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();

 protected:
  void check_params() override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  // Scratch planes kept between execute() calls (no page faults frame after frame).
  ColourPlanes cp_;
  Guides guides_;
  std::vector<float> valid_, s_, rad_, res_[3], reg_[3];
  std::vector<float> noise_a_;  // colour_weight=noise: per-pixel sqrt(k) of the colour weight
};

}  // namespace mcr
