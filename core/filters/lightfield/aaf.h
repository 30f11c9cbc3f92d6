#pragma once
// Axis-aligned filtering (Mehta et al. 2012) over light-field samples: each pixel integrates its
// own samples with w_y (its w_y-weighted mean), then a normalised spatial Gaussian along e1,
// then along e2 (one pixel steps, nearest pixel, like sheared's 1b / 2b with eta = 0), with
//     sigma_x = sigma_y min(|smin|, |smax|) / (2 mu)   (x units; Omega_x = Omega_y^max / min|s|,
//                                                       Omega_y^max = 2 / sigma_y, sigma = 1 / (mu Omega_x))
// and radius min(ceil(2 sigma_x |e_i|), max_width / 2) per axis. The slope smoothing, the
// skipped pixels and the rejection are kernels/lightfield_rules.h's. Each pass normalises its
// weights; the second pass reads the neighbours' first-pass values (their own widths).
#include "filters/filter.h"
#include "image/lightfield.h"
#include "kernels/lightfield_rules.h"

namespace mcr {

// Writes RGB (channels 0..2 of out, a lf-sized image) inside roi; counts may be null.
void aaf_lightfield(const LightField& lf, const lf::Options& o, const Roi& roi, int nthreads, Image& out,
                    lf::Counts* counts);

class AafFilter : public Filter {
 public:
  AafFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();

 protected:
  bool step_back_applies() const override { return false; }
  std::vector<std::string> own_unused() const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;
};

}  // namespace mcr
