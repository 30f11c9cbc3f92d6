#pragma once
// The vectorised kernel of the edge-avoiding filters (bilateral, atrous) and of the
// foveated Gaussian: one pass sums w(p,q) c(q) over a grid of taps around every pixel p
// of planes laid out by kernels/planes.h, with the guides of kernels/feature_guides.h:
//
//   w(p,q) = h(q-p) * valid(q) * exp(-( s(p) |q-p|^2 + sum_f k_f(p) |f(p) - f(q)|^2 ))
//   k_f = 1 / (2 sigma_f^2),  s = 1 / (2 sigma_spatial^2)
//
// i.e. G_spatial * prod_f exp(-|f(p)-f(q)|^2 / (2 sigma_f^2)) evaluated with ONE
// exponential per tap (the exponents are summed), by a fast exp accurate to
// 2e-7 relative that returns exactly 1 for 0 and exactly 0 for exponents beyond
// -86 (and for NaN or infinite ones, so an overflowing feature difference gives
// weight 0, never NaN). 4, 8 or 16 pixels are processed at once (GCC vector
// extensions), with AVX-512 or AVX2+FMA chosen at run time (util/isa.h), SSE2 otherwise.
// cross_bilateral.cpp builds and dispatches the rows; the block of W pixels is in
// cross_bilateral_block.h, the path that shares each symmetric pair's exponential in
// cross_bilateral_symmetric.h.
#include <cmath>
#include <vector>

#include "image/image.h"
#include "kernels/feature_guides.h"
#include "kernels/planes.h"

namespace mcr {

// Half width of a Gaussian window of standard deviation sigma: ceil(3 sigma), 0 for sigma 0.
inline int gaussian_radius(double sigma) { return sigma > 0 ? int(std::ceil(3.0 * sigma - 1e-6)) : 0; }

// One pass of the weighted sum. Every pointer is a plane laid out by `pb`; a null
// plane means the matching constant.
struct CrossPass {
  PlaneBox pb;
  const float* colour[3] = {nullptr, nullptr, nullptr};  // the values averaged (sanitised)
  const float* colour_ok = nullptr;  // centre usable: colour weight applies, fallback value
  const float* valid = nullptr;      // neighbour usable: 0/1 factor of its weight
  bool colour_weight = false;        // colour is also a guide (compared against the centre)
  const float* colour_a = nullptr;   // per-pixel sqrt(k) of the colour weight, or colour_a_const ...
  float colour_a_const = 0.0f;       // (the colour term is sum_c (a (c_p - c_q))^2: no under- or
  float colour_amul = 1.0f;          // overflow of a^2) ... times this (1/scale, atrous sigma decay)
  std::vector<const Guides::Guide*> guides;  // other features (at most 3 three-channel + depth)
  const float* s = nullptr;          // per-pixel spatial coefficient, or s_const (0 = none)
  float s_const = 0.0f;
  const float* radius = nullptr;     // per-pixel square window radius; null = the whole grid
  std::vector<int> off;              // 1D tap offsets, ascending, symmetric; taps = off x off
  std::vector<float> h;              // 1D tap weights; the tap weight is h[i] * h[j]
  float* out[3] = {nullptr, nullptr, nullptr};
  float* out_ok = nullptr;           // optional: 1 where the result holds data
  float* out_valid = nullptr;        // optional: out_ok * valid_mask, the next pass' valid
  const float* valid_mask = nullptr; // (written with the result: no extra sweep per pass)

  // Unit-weight taps at every offset in [-rmax, rmax] (the dense kernels of
  // gaussian and bilateral; the spatial weight comes from s).
  void set_dense_taps(int rmax) {
    off.clear();
    h.clear();
    for (int k = -rmax; k <= rmax; ++k) {
      off.push_back(k);
      h.push_back(1.0f);
    }
  }
};
// For every pixel p of `region` (inside pb.box): sum w(p,q) c(q) / sum w(p,q) over the
// taps inside the image (clipped and renormalised at the borders). A pixel whose
// taps all have weight 0 gets its own colour when colour_ok, else 0 (out_ok = 0).
// Deterministic: results do not depend on nthreads or on the region's placement
// (the instruction set chosen at run time may change the last bits: FMA). With no
// per-pixel colour a, k, s or window and at most 5 x 5 taps (atrous), each pair's
// exp(-e) is computed once and shared by both pixels (e is symmetric bit for bit):
// the same result, with half the exponentials.
void cross_filter(const CrossPass& pass, const Roi& region, int nthreads);

// The instruction set is util/isa.h's isa(): avx512 (16 lanes, FMA), avx2 (8 lanes, FMA)
// or generic (4 lanes, SSE2 on x86-64); results agree within FMA rounding.

// exp(-e) as the kernel computes it (for tests): exact 1 at 0, 0 for e >= 86 or NaN.
float fast_exp_neg(float e);

}  // namespace mcr
