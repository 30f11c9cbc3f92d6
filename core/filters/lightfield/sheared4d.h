#pragma once
// Brute-force 4D sheared filter (Yan et al. 2015 eq. 9), the reference for the factored
// filter: for output pixel P every sample k of every pixel Q in P's window, with Q - P =
// d1 e1(P) + d2 e2(P) (x units) and |d_i| |e_i| <= r_i, weighs
//     w_x(d1) w_x(d2) w_y(y1_k + eta d1) w_y(y2_k + eta d2)
// (kernels/lightfield_rules.h: eta, sigma_x, r_i per pixel, the fallback, the skipped pixels,
// the rejection); output sum(w f) / sum(w) per channel. O(n^2 l^2) per pixel.
#include "filters/filter.h"
#include "image/lightfield.h"
#include "kernels/lightfield_rules.h"

namespace mcr {

// Writes RGB (channels 0..2 of out, a lf-sized image) inside roi; counts may be null.
void sheared4d_lightfield(const LightField& lf, const lf::Options& o, const Roi& roi, int nthreads, Image& out,
                          lf::Counts* counts);

class Sheared4dFilter : public Filter {
 public:
  Sheared4dFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();

 protected:
  bool step_back_applies() const override { return false; }
  std::vector<std::string> own_unused() const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;
};

}  // namespace mcr
