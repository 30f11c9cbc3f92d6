#pragma once
// Soft shadows seen through a thin lens (Yan et al. 2015, appendix: multiple effects): the soft
// shadows scene, each of a pixel's l x l samples a ray through its own lens stratum that meets
// one point of the light, the light's strata shuffled over the lens strata per pixel (both
// stratified). A sample's value is its texture times its light (soft_shadows.h's f); the file
// keeps the texture, the lens coordinate and the lens bounds beside the shadow's
// (LightField::lens), so a filter can take the light out, shear it as soft shadows, put the
// texture back and shear the result as depth of field.
#include <memory>

#include "camera.h"
#include "generator.h"
#include "soft_shadows.h"

namespace mcr::lfgen {

class SoftShadowsDof : public LightFieldGenerator {
 public:
  // focus_m: camera depth of the focus plane; aperture_radius_m: the lens radius (lens
  // coordinate 1), the aperture a Gaussian of sigma 1/2 over [-1, 1]^2 as in the dof scene.
  SoftShadowsDof(std::unique_ptr<SoftShadows> shadows, double focus_m, double aperture_radius_m);

  LightFieldEffect effect() const override { return LightFieldEffect::SoftShadows; }
  double y_range() const override { return shadows_->y_range(); }
  double sigma_y() const override { return shadows_->sigma_y(); }
  bool has_lens() const override { return true; }
  int width() const override { return shadows_->width(); }
  int height() const override { return shadows_->height(); }
  void render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const override;
  std::map<std::string, std::string> attributes() const override;

 private:
  std::unique_ptr<SoftShadows> shadows_;
  double focus_m_, aperture_m_;
};

// The soft shadows scene, its ground a checker of half-unit squares (texture for the lens to
// blur), through a lens focused on the ground under the light (7 m), aperture radius 0.35 m: the
// near ground and the far ground blur by up to about 3 and 5 pixels per unit of lens coordinate
// at 128 pixels wide.
std::unique_ptr<LightFieldGenerator> make_soft_shadows_dof(int width, int height);

}  // namespace mcr::lfgen
