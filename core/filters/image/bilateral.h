#pragma once
#include "filters/filter.h"
#include "kernels/cross_bilateral_fit.h"

namespace mcr {

// Cross-bilateral filter (Immonen 2017, 3.4 and 5.3), order 0 or 1: the filter around
// kernels/cross_bilateral_fit.h, which says what it computes.
class BilateralFilter : public Filter {
 public:
  BilateralFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  double band_work_bytes() const override { return 192; }

 protected:
  void check_params() override;
  std::vector<std::string> own_unused() const override;
  Roi reads(const Roi& roi, int width, int height) const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;

 private:
  CrossBilateralScratch scratch_;
};

}  // namespace mcr
