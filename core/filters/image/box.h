#pragma once
#include "filters/filter.h"

namespace mcr {

// Plain box filter: mean of the colour over a (2r+1)^2 window clipped at the
// borders. The baseline every other filter must beat, and the I/O floor probe.
class BoxFilter : public Filter {
 public:
  BoxFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();
  double band_work_bytes() const override { return 144; }

 protected:
  Roi reads(const Roi& roi, int width, int height) const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;
};

}  // namespace mcr
