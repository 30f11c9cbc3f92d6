#pragma once
// Shared machinery of the edge-avoiding filters (bilateral, atrous) and of the
// foveated Gaussian: the per-feature parameter block, the feature guides (planar
// copies, kernels/planes.h, made once per execute), and one vectorised kernel that
// sums w(p,q) c(q) over a grid of taps around every pixel p:
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
//
// Features and their on/off convention (the help text of every use_<f>):
//   use_<f> = auto  used when the frame has the pass; when it has not, the weight is
//                   dropped with a note() (colour always exists: auto = on)
//           = on    required: a frame without the pass is an error (Errc::MissingPass)
//           = off   not used
//   <f>_sigma > 0   sigma of that weight, in the pass' units (colour: radiance as
//                   filtered, i.e. after demodulation; normal: unit vectors; position,
//                   depth: scene units; albedo: reflectance)
// Normals are Blender's filtered camera-space Denoising Normal (Prefer::Feature),
// positions world space, depth its first channel.
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "kernels/foveation.h"
#include "kernels/planes.h"
#include "util/params.h"
#include "image/pass.h"

namespace mcr {

enum class Feature { Colour, Normal, Position, Albedo, Depth };
inline constexpr int kFeatureCount = 5;
const char* feature_name(Feature f);  // "colour", "normal", "position", "albedo", "depth"

struct FeatureDefaults {
  double sigma[kFeatureCount] = {2.0, 0.2, 0.2, 0.1, 0.1};
  const char* use[kFeatureCount] = {"auto", "auto", "auto", "auto", "off"};
};

// The per-feature block: use_<f> and <f>_sigma for the five features, in order.
ParamTable feature_params(const FeatureDefaults& defaults = {});
// {"colour_sigma", "normal_sigma", ...}: the names to pass to with_foveation().
std::vector<std::string> feature_sigma_names();

// The feature guides of one execute(): every enabled feature whose pass exists,
// copied to planes once. k_f(p) = 1/(2 sigma_f(p)^2) with the foveated sigma of
// each pixel, and 0 where p's own value of f is not finite (that pixel then
// ignores feature f as a centre); stored as one constant unless it varies.
struct Guides {
  struct Guide {
    Feature feature = Feature::Normal;
    int channels = 3;
    std::vector<float> c[3];  // non-finite values hold 0
    float k_const = 0.0f;     // k everywhere when the plane k is empty
    std::vector<float> k;
  };
  PlaneBox pb;
  bool colour = false;            // colour weight on
  float colour_a_const = 0.0f;    // sqrt(k) = 1/(sqrt(2) sigma) of the colour weight (unscaled colour) ...
  std::vector<float> colour_a;    // ... per pixel when foveated
  std::vector<Guide> list;        // enabled non-colour features present in the frame, Feature order
  std::vector<float> ok;          // 1 where every guide in list is finite, else 0
  std::vector<std::string> used;  // names of the features in use, colour first
};
// Reads use_<f>/<f>_sigma (and the _outer twins when foveated). Features set to
// "auto" whose pass is absent are dropped through note(); "on" ones throw MissingPass.
// Fills `g`, reusing the memory it holds from an earlier call.
void gather_guides(const Frame& frame, const ParamSet& params, const Foveation& fov, const std::string& filter,
                   const PlaneBox& pb, const std::function<void(std::string)>& note, int nthreads, Guides& g);

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
