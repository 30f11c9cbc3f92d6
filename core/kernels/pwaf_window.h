#pragma once
// The weighted mean of pwaf (Guo & Pan 2012, eq. 1 with the weight of eq. 8), W pixels of a
// row at once: every pixel p has its own square window of radius r(p), and
//
//   w(p,q) = valid(q) * exp(-(e(p,q) - e_min(p))),
//   e(p,q) = sp(|dx|,|dy|) + sum_c (a(p) (ref_c(p) - c_q))^2 + sum_k [f_k finite at p and q] k_k |f_k(p) - f_k(q)|^2
//
// with e_min(p) the smallest exponent of p's window: weights relative to the largest one,
// so a window never sums to 0 through underflow (the same mean). The result is
// c(p) + sum w (c_q - c(p)) / sum w, written as a deviation from the pixel's own colour so
// that a constant image, and a window of one pixel, give back their input bit for bit.
// Floats throughout (exp_neg_v: 2e-7 relative; deviations summed, not values), no a*b+c
// contraction: the generic, AVX2 and AVX-512 builds give the same bits, so results do not
// depend on the instruction set, the thread count or where a region starts.
#include <vector>

#include "image/image.h"
#include "kernels/planes.h"

namespace mcr {

struct PwafWindowPass {
  PlaneBox pb;                                    // every plane's layout (the roi grown by the radius)
  const float* colour[3] = {nullptr, nullptr, nullptr};  // neighbour values (0 where not valid)
  const float* valid = nullptr;                   // 1: a usable neighbour, 0: never weighted
  const float* ref[3] = {nullptr, nullptr, nullptr};     // centre: the range value compared against
  const float* a = nullptr;                       // centre: sqrt of the colour coefficient
  const float* radius = nullptr;                  // centre: window radius (an integer, as float)
  int features = 0;                               // at most 3 three-channel features
  const float* feature[3][3] = {};                // their planes (NaN where not finite: the pair's term is left out)
  float k[3] = {0, 0, 0};                         // 1 / (2 sigma^2) of each
  int max_radius = 0;
  std::vector<float> spatial;                     // exponent at (|dx|, |dy|): [|dy| * (max_radius + 1) + |dx|]
  float* out[3] = {nullptr, nullptr, nullptr};    // the result at every pixel of the region
  float* out_ok = nullptr;                        // 0 where the window held no valid pixel (out 0)
};

// Fills out over `region` (inside pb.box); rows in parallel.
void pwaf_window_filter(const PwafWindowPass& pass, const Roi& region, int nthreads);

}  // namespace mcr
