#pragma once
// Soft shadows from a square area light of Gaussian intensity (Yan et al. 2015 sec. 3.1):
// y is the light point in world units along the light's axes a1, a2, f the unshadowed
// diffuse shading times visibility, s = d1/d2 - 1 per occluded sample.
#include <memory>

#include "camera.h"
#include "generator.h"
#include "scene.h"

namespace mcr::lfgen {

struct SoftShadowsSetup {
  Camera camera;
  Vec3 light_centre;
  Vec3 a1, a2;            // orthonormal; the light emits along a1 x a2 (towards the scene)
  double half_side = 0.5;  // L: the light is [-L, L]^2, sigma_y = L / 2
  double radiance = 1;     // f = albedo / pi * cos_r * cos_l / r^2 * radiance
};

class SoftShadows : public LightFieldGenerator {
 public:
  explicit SoftShadows(const SoftShadowsSetup& setup) : s_(setup) {}
  Scene& scene() { return scene_; }  // add shapes, then commit()
  const Scene& scene() const { return scene_; }
  const SoftShadowsSetup& setup() const { return s_; }
  void commit() { scene_.commit(); }

  // One light point (u1, u2) seen from receiver h: f, the light without the texture
  // (radiance / pi cos_r cos_l / r^2), 0 where occluded (then `occluded` and the slope).
  struct LightSample {
    double f = 0;
    bool occluded = false;
    double slope = 0;  // d1/d2 - 1
  };
  LightSample light_sample(const Hit& h, double u1, double u2) const;
  // The light at h with nothing in the way, times `texture`: the Gaussian-weighted mean over a
  // 16 x 16 grid of the light (no rays: smooth, so the grid is converged).
  Vec3 unoccluded(const Hit& h, const Vec3& texture) const;
  // The receiver's axes: world duals w1, w2 and their screen lengths e1, e2.
  void receiver_axes(const Hit& h, PixelSamples& out) const;

  LightFieldEffect effect() const override { return LightFieldEffect::SoftShadows; }
  double y_range() const override { return s_.half_side; }
  double sigma_y() const override { return 0.5 * s_.half_side; }
  int width() const override { return s_.camera.width; }
  int height() const override { return s_.camera.height; }
  void render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const override;
  std::map<std::string, std::string> attributes() const override;

 private:
  SoftShadowsSetup s_;
  Scene scene_;
};

// The default scene: a ground plane under a light 4 units up (side 1.2, axes turned 20 degrees
// about the vertical), a sphere, a thin bar and a box on the ground.
std::unique_ptr<LightFieldGenerator> make_soft_shadows(int width, int height);
// The same scene as its own type (the combined scene looks at it through a lens), the ground a
// checker of squares ground_checker units wide (0.8 and (0.35, 0.3, 0.25)) unless 0 (plain).
std::unique_ptr<SoftShadows> make_soft_shadows_scene(int width, int height, double ground_checker = 0);

}  // namespace mcr::lfgen
