#pragma once
// Light-field samples (Yan et al. 2015): per pixel l x l samples of f(x, y), x the pixel
// (receiver) and y a 2D coordinate on the light, the lens or the v-plane, with the pixel's
// slope bounds. Decoded from / encoded to a deep EXR (README: the light-field convention).
//
// One convention for the three effects (what the filters rely on): a sample taken at pixel
// x' with coordinate y' carries the value that pixel x would see at
//     y = y' - (x - x') / s            (per axis, x in "x units", s the local slope)
// where x units are world units along the receiver for soft shadows and indirect light
// (screen pixels per x unit in e1, e2) and pixels for depth of field (e1 = (1,0), e2 = (0,1)):
//   soft shadows:  s = d1/d2 - 1   (d1: light to receiver, d2: light to occluder), y on the
//                  light in world units, Gaussian light of standard deviation sigma_y;
//   depth of field: s = -c, c the circle of confusion radius in pixels per unit of lens
//                  coordinate (signed: positive behind the focus plane), y on the lens,
//                  Gaussian aperture of standard deviation sigma_y;
//   indirect light: s = z, the reflector's distance from the receiver along the normal, y on
//                  the v-plane at unit distance (tangent of the direction), values already
//                  weighted by the diffuse transfer over the sampling pdf (their plain mean is
//                  the pixel), a box over y: the v-plane truncation [-L, L]^2; sigma_y = 2 /
//                  Omega_v^max (about 0.71) sets only the spatial width.
// Spatial standard deviation (x units) from the bounds, eq. 4: sigma_x = sigma_y * smin * smax /
// (smax - smin); the shear (primal, this convention): eta = (1/smin + 1/smax) / 2, the weight of
// a sample for pixel x being w_x(x' - x) w_y(y' + eta (x' - x)) per axis.
// A pixel's bounds [smin, smax] span the slopes its samples saw; smin = smax = 0 says
// nothing to shear (unoccluded, in focus, no reflector).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "image/deep.h"

namespace mcr {

enum class LightFieldEffect { SoftShadows, Dof, Gi };
const char* effect_name(LightFieldEffect e);  // "soft_shadows", "dof", "gi"

struct LightField {
  LightFieldEffect effect = LightFieldEffect::SoftShadows;
  int width = 0, height = 0;
  int l = 0;            // samples per axis: every pixel holds l*l samples
  float y_range = 1;    // L: y sampled over [-L, L]^2 (uniform jittered strata)
  float sigma_y = 0.5;  // Gaussian standard deviation over y (soft shadows, dof); gi: 2 / Omega_v^max

  // Per sample, index pixel * l*l + k (pixel = y * width + x; k in any order).
  std::vector<float> r, g, b;   // f(x, y): the sample's value, not weighted by the light/lens
  std::vector<float> y1, y2;    // the sample's coordinate on the light / lens / v-plane

  // Per pixel.
  std::vector<float> smin, smax;          // slope bounds (both 0: nothing to shear)
  std::vector<float> e1x, e1y, e2x, e2y;  // screen displacement in pixels per x unit along x1, x2
  std::vector<float> depth;               // receiver depth along the view ray (first hit)
  std::vector<float> px, py, pz;          // receiver world position (empty when the file has none)
  std::vector<float> nx, ny, nz;          // receiver world normal, unit (empty when absent)
  // World dual axes (empty when absent; only with geometry): a world displacement D of the
  // receiver is D . w1, D . w2 in x units (soft shadows: the light's axes; gi: the receiver's
  // tangent axes). With them the filters take a neighbour's displacement from the positions,
  // exact under perspective, instead of the screen linearisation e1, e2 (which is off by 5% at
  // 5 pixels on an oblique ground, enough to shear a shadow wrongly at 16).
  std::vector<float> w1x, w1y, w1z, w2x, w2y, w2z;
  // Modulation (empty when absent): what the pixel would be with nothing in the way (soft
  // shadows: the unoccluded direct light, RGB). The filters then shear f / mod, the visibility
  // (Mehta et al. 2012, Yan et al. 3.1: the sheared spectrum is the visibility's), and multiply
  // the result by the pixel's mod: the shading's own change across a 32-pixel window is not
  // carried from a neighbour into the pixel (it left bright and dark rings around shadows).
  std::vector<float> mod_r, mod_g, mod_b;

  // Soft shadows and depth of field together (Yan et al. 2015, appendix; the file's effect
  // "soft_shadows+dof"): this light field is then the soft shadows' (y on the light, the shadow
  // bounds and axes, mod the unoccluded light without the texture) with r, g, b each sample's
  // whole value, and `lens` the same samples on the lens: effect Dof, y1, y2 the lens
  // coordinate, r, g, b the texture k at the sample's hit (the whole value = k x the light
  // there), smin, smax the lens slope bounds, e1 = (1, 0), e2 = (0, 1), the same depth, no
  // geometry. Null for one effect. A pixel's estimate weighs a sample by the light's and the
  // aperture's weights together.
  std::shared_ptr<const LightField> lens;

  std::size_t nonfinite_replaced = 0;     // sample values decode replaced (non-finite)

  int spp() const { return l * l; }
  std::size_t pixels() const { return std::size_t(width) * std::size_t(height); }
  std::size_t samples() const { return pixels() * std::size_t(spp()); }
  bool has_geometry() const { return !px.empty() && !nx.empty(); }
  bool has_world_axes() const { return has_geometry() && !w1x.empty(); }
  bool has_modulation() const { return !mod_r.empty(); }
  bool combined() const { return lens != nullptr; }
  // Allocates every array for width x height x l*l (geometry and world axes too when `geometry`).
  void resize(int w, int h, int l_, bool geometry);
};

// The deep EXR form: per-sample channels R G B lf.y1 lf.y2, and per-pixel values repeated on
// each sample: lf.smin lf.smax lf.e1x lf.e1y lf.e2x lf.e2y Z, optionally P.X P.Y P.Z N.X N.Y N.Z
// and with them lf.w1x lf.w1y lf.w1z lf.w2x lf.w2y lf.w2z; optionally lf.modR lf.modG lf.modB;
// header attributes mcrecon:lightfield (effect), mcrecon:lf_l, mcrecon:lf_y_range,
// mcrecon:lf_sigma_y. Combined ("soft_shadows+dof"): also per sample lf.u1 lf.u2 (lens) and
// lf.kR lf.kG lf.kB (texture), per pixel lf.dmin lf.dmax (lens bounds), mcrecon:lf_u_range and
// mcrecon:lf_sigma_u.
bool is_lightfield(const DeepSamples& deep);  // carries mcrecon:lightfield
// The file's name of what lf holds: effect_name, or "soft_shadows+dof" when combined.
std::string lightfield_kind(const LightField& lf);
// The weight over one axis of y: the Gaussian light or aperture, exp(-y^2 / (2 sigma_y^2)), or
// for gi the v-plane truncation (1 inside [-L, L], else 0). A pixel's unfiltered estimate is
// the mean of its samples weighted by w(y1) w(y2).
float lightfield_y_weight(LightFieldEffect effect, float sigma_y, float y_range, float y);
// Sample k's weight in its pixel's unfiltered estimate: w(y1) w(y2) (combined: times the
// aperture's weight of its lens coordinate).
float lightfield_sample_weight(const LightField& lf, std::size_t k);
// Throws Error (BadInput / MissingPass) naming `path` and what is wrong: a missing channel or
// attribute, a pixel without exactly l*l samples, a non-finite or out-of-range coordinate, a
// non-finite slope or axis, l outside 1..64. A non-finite value (or texture) takes its pixel's
// finite mean (0 when none) and is counted.
LightField decode_lightfield(const DeepSamples& deep, const std::string& path, std::size_t* nonfinite_values = nullptr);
DeepSamples encode_lightfield(const LightField& lf);

// All l*l samples of pixel p and of its 8 neighbours (those inside the image) carry the same
// colour (never with l = 1). The pixel's own samples alone agree by chance where few of them meet
// a fine pattern (4 samples of a slightly defocused checker, of a penumbra): such pixels were
// kept as their own samples beside filtered neighbours, salt and pepper (dof at 4 spp: sheared
// 0.0214 with the own-samples rule, 0.0070 with the 3x3 one; at 64 spp 0.00118 / 0.00117).
bool lightfield_converged(const LightField& lf, std::size_t p);

// What `mcrecon info` says of a light field: its slopes and how many pixels need shearing.
struct LightFieldSummary {
  float slope_min = 0, slope_max = 0;  // over the pixels with bounds
  std::size_t nothing_to_shear = 0;     // smin = smax = 0 (unoccluded, in focus)
  std::size_t opposite_signs = 0;       // smin * smax < 0 (depth of field across the focus plane)
  std::size_t converged = 0;            // lightfield_converged: the filters keep their own samples
  float e1_mean = 0, e2_mean = 0;       // mean screen length of one x unit along x1, x2 (pixels)
};
LightFieldSummary summarize(const LightField& lf);

}  // namespace mcr
