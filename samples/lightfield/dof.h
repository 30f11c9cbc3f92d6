#pragma once
// Depth of field through a thin lens with a Gaussian aperture: y is the lens point in units of
// the aperture radius on [-1, 1]^2 (sigma_y = 1/2), along the image's +x and +y, f the radiance
// seen, s = -c with c the image displacement in pixels per unit of lens coordinate of the
// point hit: c = A s_f (1/F - 1/z) / pitch (positive behind the focus plane).
#include <memory>

#include "camera.h"
#include "generator.h"
#include "scene.h"

namespace mcr::lfgen {

struct ThinLens {
  double lens_mm = 50, fstop = 2, focus_m = 2, sensor_width_mm = 36;
  double aperture_radius_m() const { return lens_mm / 1000 / (2 * fstop); }
  double sensor_distance_m() const;  // s_f: 1/f = 1/F + 1/s_f
  // Pixels per unit of lens coordinate that a point at camera depth z (metres) moves.
  double image_shift_px(double z_m, int width) const;
};

struct DofSetup {
  Camera camera;  // eye, axes and size; focal_px is set from the lens
  ThinLens lens;
  Vec3 light_dir{0, 0, 1};  // towards the directional light (unit), no shadows
  Vec3 background{0, 0, 0};
};

class Dof : public LightFieldGenerator {
 public:
  explicit Dof(const DofSetup& setup);
  Scene& scene() { return scene_; }
  void commit() { scene_.commit(); }
  const Camera& camera() const { return s_.camera; }
  // The ray of image point (px, py) through lens point (u1, u2) (lens-radius units, along
  // the image's +x, +y): from that lens point to the point's focus on the plane at depth F.
  void lens_ray(double px, double py, double u1, double u2, Vec3& org, Vec3& dir) const;

  LightFieldEffect effect() const override { return LightFieldEffect::Dof; }
  double y_range() const override { return 1.0; }
  double sigma_y() const override { return 0.5; }
  int width() const override { return s_.camera.width; }
  int height() const override { return s_.camera.height; }
  void render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const override;
  std::map<std::string, std::string> attributes() const override;

 private:
  Vec3 shade(const Hit& h) const;
  DofSetup s_;
  Scene scene_;
};

// The default scene: an 85 mm f/1.2 lens focused at 2.5 m on a checker ground, a small
// sphere at 1.2 m, one in focus, one at 5 m and a checker wall at 8 m.
std::unique_ptr<LightFieldGenerator> make_dof(int width, int height);

}  // namespace mcr::lfgen
