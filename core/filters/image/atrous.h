#pragma once
#include "kernels/feature_guides.h"
#include "kernels/planes.h"
#include "filters/filter.h"

namespace mcr {

// Edge-avoiding A-Trous wavelet filter (Dammertz et al. 2010; Immonen 2017, 4.1,
// 5.3, 5.4): `iterations` passes of a cross-bilateral filter whose spatial part is
// the k_g-tap generating kernel h (outer product h x h) dilated by 2^(i-1) in pass i
// ("holes" between the taps), so the effective kernel grows as k_g 2^(i-1) at a
// constant cost per pass. Each pass compares the colour of its own input (the
// previous pass' output); normals, positions, albedo and depth stay the frame's.
class AtrousFilter : public Filter {
 public:
  AtrousFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  double band_work_bytes() const override { return 208; }
  // The 1D generating kernel for k_g = 3, 5 or 9 (sums to 1).
  static std::vector<float> generating_kernel(int kg);

 protected:
  void check_params() override;
  int own_reach() const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  // Scratch planes kept between execute() calls (no page faults frame after frame).
  ColourPlanes cp_;
  Guides guides_;
  std::vector<float> next_[3], next_ok_, valid_, next_valid_;
  std::vector<float> noise_a_;  // colour_weight=noise: per-pixel sqrt(k) of the colour weight
};

}  // namespace mcr
