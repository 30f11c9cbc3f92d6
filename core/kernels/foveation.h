#pragma once
// Foveation (Immonen 2017, section 5.3 and figure 5.1): a filter's parameters
// are given twice, an inner set used around the point of gaze and an outer set
// used far from it, linearly interpolated between two circles centred on the gaze.
//
//   foveated      on/off; off = the inner set everywhere (the _outer twins are ignored)
//   gaze_x/gaze_y point of gaze as a fraction of the width / height (0,0 = top-left
//                 corner of the image, 0.5,0.5 = its centre)
//   inner_radius  radius of the inner circle, as a FRACTION OF THE IMAGE DIAGONAL
//   outer_radius  radius of the outer circle, same unit, >= inner_radius
//
// With d the distance in pixels from the pixel centre (x+0.5, y+0.5) to the gaze
// (gaze_x*width, gaze_y*height) and R = diagonal = sqrt(width^2 + height^2):
//   t = 0 for d <= inner_radius*R, 1 for d >= outer_radius*R, linear between
//   (t = 0/1 step at the circle when both radii are equal), and
//   P(x,y) = P_inner + t * (P_outer - P_inner)   for every foveated parameter P.
//
// A filter declares its foveated parameters in one line,
//   i.params = with_common_params(with_foveation({...own table...}, {"sigma"}));
// which inserts "sigma_outer" (same type, range and default) right after "sigma"
// and appends the five parameters above.
#include <string>
#include <vector>

#include "util/params.h"
#include "image/image.h"

namespace mcr {

// Inserts a "<name>_outer" twin after each named Float parameter of `own` and
// appends foveated, gaze_x, gaze_y, inner_radius, outer_radius.
ParamTable with_foveation(ParamTable own, const std::vector<std::string>& foveated_params);

// Cross-parameter check (outer_radius >= inner_radius when foveated); throws
// Errc::ParameterOutOfRange naming the filter. Call from check_params().
void check_foveation_params(const ParamSet& params, const std::string& filter);

// Without foveated=true: every _outer twin, gaze_x, gaze_y, inner_radius, outer_radius given
// ("sigma_outer has no effect with foveated=false").
std::vector<std::string> foveation_unused(const ParamSet& params);

// The inner/outer pair of one parameter, looked up once (not per pixel).
struct FoveatedValue {
  double inner = 0, outer = 0;
  bool varies = false;  // foveated and inner != outer
  double at(float t) const {
    if (!varies || t <= 0.0f) return inner;
    if (t >= 1.0f) return outer;
    return inner + double(t) * (outer - inner);
  }
};

class Foveation {
 public:
  Foveation(const ParamSet& params, int width, int height);

  bool enabled() const { return enabled_; }
  // Interpolation weight t of the point (px, py) in pixel units (0 = inner set).
  float blend(double px, double py) const;
  float blend_at(int x, int y) const { return blend(x + 0.5, y + 0.5); }

  // P_inner + t (P_outer - P_inner) for the Float parameter `name`.
  double value(const std::string& name, float t) const { return param(name).at(t); }
  FoveatedValue param(const std::string& name) const;
  double inner(const std::string& name) const;
  double outer(const std::string& name) const;
  // True when the parameter is not the same everywhere (foveated and inner != outer).
  bool varies(const std::string& name) const;
  // t for every pixel of `box` (row-major, box.width() per row); all 0 when not enabled.
  std::vector<float> blend_plane(const Roi& box) const;

 private:
  const ParamSet& params_;
  bool enabled_ = false;
  double gx_ = 0, gy_ = 0, r_in_ = 0, r_out_ = 0;  // pixels
};

}  // namespace mcr
