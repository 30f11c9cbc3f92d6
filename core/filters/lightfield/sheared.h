#pragma once
// Fast 4D sheared filter (Yan et al. 2015 sec. 4.3): the 4D filter of sheared4d factored into
// four 1D steps, O(n l) per pixel instead of O(n^2 l^2). Same rules and weights as sheared4d
// (kernels/lightfield_rules.h); B bins (parameter, 16) of the filter centre b over
// [-(y_range + 2 sigma_y), y_range + 2 sigma_y] (gi: [-2 y_range, 2 y_range]).
//   1a  per pixel Q, per distinct y2 of its samples:  p_Q(b, y2) = sum_i f_i w_y(y1_i - b)
//       (and the weight sum alike), at the B bin centres;
//   1b  per pixel P, along P + t e1(P), t_j = j / |e1(P)|, j = -r1..r1 (nearest pixel Q_j):
//       g_P(y2) = sum_j w_x(t_j) p_{Q_j}(-eta_P t_j, y2), each source y2 scattered into P's B
//       y2 bins (linear between bin centres, clamped at the ends: footnotes 8, 9);
//   2a  q_P(c) = sum_b2 g_P(b2) w_y(centre(b2) - c), c at the bin centres;
//   2b  h_P = sum_j w_x(t_j) q_{Q_j}(-eta_P t_j) along P + t e2(P); output value / weight.
// Bin values are read with linear interpolation between bin centres (the paper takes the
// nearest), zero beyond the outer centres (fading to 0 half a bin out). A pixel's steps 1b-2a
// use its own rule, so a neighbour's q carries the neighbour's shear (the separable
// approximation, exact where the rule is constant); rejection is between P and Q_j in 1b
// and in 2b. Memory: per pixel B * 16 bytes per distinct y2 (l of them under uniform jitter)
// for p and B * 16 for q; the output rows go in bands whose p and q fit in
// lf::Options::band_bytes (512 MB), the rows shared by two bands computed in both.
#include "filters/filter.h"
#include "image/lightfield.h"
#include "kernels/lightfield_rules.h"

namespace mcr {

// Writes RGB (channels 0..2 of out, a lf-sized image) inside roi; counts may be null.
void sheared_lightfield(const LightField& lf, const lf::Options& o, const Roi& roi, int nthreads, Image& out,
                        lf::Counts* counts);

class ShearedFilter : public Filter {
 public:
  ShearedFilter() : Filter(static_info()) {}
  static const FilterInfo& static_info();

 protected:
  bool step_back_applies() const override { return false; }
  std::vector<std::string> own_unused() const override;
  void run(const Frame& frame, const Image& colour, const Roi& roi, Image& out, int nthreads) override;
};

}  // namespace mcr
