#pragma once
#include "kernels/planes.h"
#include "filters/filter.h"

namespace mcr {

// Simple Blur (Immonen 2017, 3.2 and 5.3): Gaussian of standard deviation sigma
// over a (2r+1)^2 window, r = ceil(3 sigma), clipped and renormalised at the image
// borders. Separable (two 1D passes) wherever sigma is the same for every pixel;
// foveated with sigma != sigma_outer it runs the exact per-pixel kernel
// (each pixel its own sigma and radius, not separable).
class GaussianFilter : public Filter {
 public:
  GaussianFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  double band_work_bytes() const override { return 184; }

 protected:
  void check_params() override;
  Roi reads(const Roi& roi, int width, int height) const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  void run_separable(const Image& colour, double sigma, const Roi& roi, Image& out, int nthreads);
  void run_per_pixel(const Image& colour, const Roi& roi, Image& out, int nthreads);

  // Scratch planes kept between execute() calls (no page faults frame after frame).
  ColourPlanes cp_;
  std::vector<float> hz_[4], res_[3], s_, rad_;
};

}  // namespace mcr
