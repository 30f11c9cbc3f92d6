#pragma once
// What the light-field filters (filters/lightfield/: sheared4d, sheared, aaf) share: each
// pixel's filter rule from its slope bounds (Yan et al. 2015 eq. 4, 5 in the convention of
// image/lightfield.h; Mehta et al. 2012 for the axis-aligned rule), the slope smoothing of
// soft shadows (sec. 5), the weights over y, a pixel's own weighted mean, the rejection of
// neighbours across geometry edges, and the walk along a screen axis one pixel at a time.
//
// Per pixel P with bounds lo = min(smin, smax), hi = max(smin, smax):
//   sheared rule (lo * hi > 0):  eta = (1/lo + 1/hi) / 2,  sigma_x = sigma_y lo hi / (hi - lo)
//                                (x units; lo == hi: infinite, the Gaussian is flat and the
//                                support is the max_width cap);
//   axis-aligned rule:           eta = 0, sigma_x = sigma_y min(|lo|, |hi|) / (2 mu)
//                                (Mehta 2012: sigma = 1 / (mu Omega_x), Omega_x =
//                                Omega_y^max / min|s|, Omega_y^max = 2 / sigma_y);
//   support radius per axis i:   r_i = min(ceil(2 sigma_x |e_i|), max_width / 2) pixels.
// A pixel with lo == hi == 0 (after smoothing) has nothing to filter: its output is its own
// w_y-weighted sample mean, as is a converged pixel's (all samples equal; its samples still
// serve its neighbours) and a pixel whose axes e1, e2 are degenerate (length 0 or parallel).
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "image/image.h"
#include "image/lightfield.h"

namespace mcr::lf {

struct Options {
  int max_width = 32;         // widest support, pixels (a diameter): r_i <= max_width / 2
  bool reject = true;         // reject neighbours across geometry edges (soft shadows, gi with geometry)
  float normal_degrees = 20;  // ... whose normal differs by more than this
  int smooth_radius = 2;      // soft shadows: slope smoothing window (2 = 5x5); 0 = off
  int bounds_radius = -1;     // every pixel's bounds widened to those of its (2r+1)^2 window; 0 = own;
                              // -1 = smooth_radius for soft shadows, 0 otherwise
  bool fallback_aaf = true;   // lo * hi <= 0 (not both 0): the axis-aligned rule (else own mean)
  float mu = 1;               // the axis-aligned rule's mu
  int bins = 16;              // sheared (factored): bins over b and y2
  // The result's residual against each pixel's own samples added back (kernels/residual_shrink.h):
  double residual_k = -1;     // 0 = off, -1 = by effect (residual_k_for)
  int residual_radius = 0;    // 0 = by samples (residual_radius_for)
  // The step back toward each pixel's own estimate (kernels/risk_blend.h) with the variance of
  // its samples (kernels/lightfield_variance.h), and the half width of its window.
  enum class StepBack { ByEffect, Off, Strata, Samples } step_back = StepBack::ByEffect;
  int step_back_radius = 3;
  // Soft shadows through a lens (LightField::lens): the light each sample takes into the lens
  // stage: its pixel's filtered light alone (true: the appendix of Yan et al. 2015), or that plus
  // its own departure from its pixel's mean (false).
  bool combined_per_pixel = true;
  // sheared (factored): memory for a band of rows' pre-convolved values (steps 1a, 2a); rows
  // beyond it go to further bands (same result). Not a parameter; tests make it small.
  std::size_t band_bytes = std::size_t(512) << 20;
};

// How a pixel is filtered (its rule also serves its neighbours in the factored filter).
enum class Kind : unsigned char { Sheared, AxisAligned, Own };

struct Rule {
  Kind kind = Kind::Own;
  bool own_output = true;  // the output is the pixel's own w_y-weighted mean
  float eta = 0;           // shear: sample weight w_y(y' + eta d) per axis
  float inv2sx2 = 0;       // 1 / (2 sigma_x^2), x units^-2; 0 = flat (sigma infinite) or r = 0
  int r1 = 0, r2 = 0;      // support radius, pixels along e1, e2
  float len1 = 0, len2 = 0;  // |e1|, |e2|: pixels per x unit
};

struct Counts {
  std::size_t pixels = 0;       // output pixels (the roi)
  std::size_t own = 0;          // nothing to shear after smoothing: own samples
  std::size_t converged = 0;    // all samples equal: own samples
  std::size_t degenerate = 0;   // e1, e2 of length 0 or parallel: own samples
  std::size_t fallback = 0;     // lo * hi <= 0, not both 0 (sheared filters): the fallback rule
  std::size_t zero_weight = 0;  // every weight 0 (all neighbours rejected, box missed): own samples
  std::size_t smoothed = 0;     // soft shadows: bounds taken from the smoothing window
};

enum class Mode { Sheared, AxisAligned };

// The rule of every pixel of lf (soft shadows: after slope smoothing). Counts are of the
// pixels inside `roi` (the pixels the filter writes). Throws Error(InvalidArgument) when
// sigma_y or y_range is not a positive finite number, Error(Internal) when an array is not
// sized for width x height x l*l (decode_lightfield sizes them).
std::vector<Rule> pixel_rules(const LightField& lf, const Options& o, Mode mode, const Roi& roi, Counts* counts);

// w_y: a Gaussian of sigma_y centred at 0 (soft shadows, dof); gi: the box |y| <= y_range. The
// Gaussian is cut at |y| = y_range too: the light (lens) ends there, so a neighbour's sample that
// maps to a point beyond it stands for no light at all (without the cut, lit pixels next to a
// shadow gathered occluded samples from outside the light: dark halos, soft_shadows 0.0017
// against 0.0005 for the input at 16 spp).
struct WeightY {
  bool box = false;
  float inv2sy2 = 0;
  float range = 1;
  explicit WeightY(const LightField& lf);
  float operator()(float y) const {
    if (!(std::fabs(y) <= range)) return 0.0f;
    return box ? 1.0f : std::exp(-y * y * inv2sy2);
  }
};

inline float weight_x(float d2, float inv2sx2) { return std::exp(-d2 * inv2sx2); }


// The pixel's own sum over its samples of f w_y(y1) w_y(y2) / the sum of the weights (their
// plain mean when every weight is 0). rgb: 3 floats.
void own_mean(const LightField& lf, const WeightY& wy, std::size_t p, float* rgb);

// Neighbour rejection (soft shadows and gi with geometry; inactive otherwise): Q is not used
// for P when their normals differ by more than normal_degrees, or when |pos_Q - pos_P| >
// 2 dist + pixel_world, dist the displacement's length in x units (world) and pixel_world
// the world size of one pixel at P (1 / min(|e1|, |e2|)), or when Q lies off P's tangent plane
// by more than pixel_world + a tenth of their distance. A zero normal rejects nothing.
class Rejection {
 public:
  Rejection(const LightField& lf, const Options& o);
  bool active() const { return active_; }
  bool rejects(std::size_t p, std::size_t q, float dist, float pixel_world) const;

 private:
  const LightField* lf_;
  bool active_ = false;
  float cos_max_ = 1;
};

// A neighbour's displacement in x units along an axis: exact from the receivers' world positions
// when the light field has world axes (x_i = (P_q - P_p) . w_i(p)), else the screen linearisation
// the caller passes (from e1, e2 at p).
class Displacement {
 public:
  explicit Displacement(const LightField& lf) : lf_(&lf), world_(lf.has_world_axes()) {}
  bool world() const { return world_; }
  float along(std::size_t p, std::size_t q, int axis, float linear) const {
    if (!world_) return linear;
    const LightField& l = *lf_;
    const float dx = l.px[q] - l.px[p], dy = l.py[q] - l.py[p], dz = l.pz[q] - l.pz[p];
    return axis == 0 ? dx * l.w1x[p] + dy * l.w1y[p] + dz * l.w1z[p] : dx * l.w2x[p] + dy * l.w2y[p] + dz * l.w2z[p];
  }

 private:
  const LightField* lf_;
  bool world_;
};

// The pixel nearest to (x, y) + j * (ux, uy) (pixel centres; (ux, uy) a unit screen step),
// false when it lies outside the w x h image.
inline bool step_pixel(int x, int y, float ux, float uy, int j, int w, int h, int* qx, int* qy) {
  const int ax = int(std::floor(float(x) + float(j) * ux + 0.5f));
  const int ay = int(std::floor(float(y) + float(j) * uy + 0.5f));
  if (ax < 0 || ay < 0 || ax >= w || ay >= h) return false;
  *qx = ax;
  *qy = ay;
  return true;
}

// "<who>: 12 of 4096 pixels had nothing to shear (own samples), 3 axis-aligned fallback ...".
std::string counts_note(const std::string& who, const Counts& c, bool sheared);

}  // namespace mcr::lf
