#pragma once
// One-bounce diffuse indirect light sampled on the v-plane (Yan et al. 2015 sec. 3.1 and 5):
// y = (v1, v2) in [-5, 5]^2, direction v1 t1 + v2 t2 + n, f = L_in gamma / pdf / C so the
// plain mean of a pixel's samples is its truncated cosine-weighted incident radiance;
// s = z, the reflector's distance along the receiver normal.
#include <memory>

#include "camera.h"
#include "generator.h"
#include "scene.h"

namespace mcr::lfgen {

constexpr double kVRange = 5;  // the v-plane truncation [-5, 5]^2

// gamma(v) = 1 / (1 + |v|^2)^2, the diffuse transfer on the v-plane.
inline double v_gamma(double v1, double v2) {
  const double q = 1 + v1 * v1 + v2 * v2;
  return 1 / (q * q);
}
// C = integral of gamma over [-a, a]^2: the projected solid angle of that square at unit
// distance (Lambert's polygon formula), 2 a acos(1 / (2 a^2 + 1)) / sqrt(1 + a^2).
double v_gamma_integral(double a);
// Maps a uniform point (u1, u2) in [0,1)^2 to the v-plane by a cubic per axis (dense near 0,
// like gamma), giving v and the sample's weight gamma(v) / pdf(v) / C.
void v_plane_sample(double u1, double u2, double& v1, double& v2, double& weight);

struct GiSetup {
  Camera camera;
  Vec3 light_pos;          // a point light, with shadow rays
  double intensity = 1;    // irradiance intensity / d^2 * cos at the reflector
};

class Gi : public LightFieldGenerator {
 public:
  explicit Gi(const GiSetup& setup) : s_(setup) {}
  Scene& scene() { return scene_; }
  void commit() { scene_.commit(); }

  LightFieldEffect effect() const override { return LightFieldEffect::Gi; }
  double y_range() const override { return kVRange; }
  double sigma_y() const override { return 2 / 2.8; }  // 2 / Omega_v^max
  int width() const override { return s_.camera.width; }
  int height() const override { return s_.camera.height; }
  void render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const override;

 private:
  Vec3 reflected(const Hit& h) const;  // diffuse radiance leaving h from the point light
  GiSetup s_;
  Scene scene_;
};

// The default scene: a 4 x 4 x 3 room open towards the camera, red left and green right
// walls, a tall box and a sphere, a point light under the ceiling.
std::unique_ptr<LightFieldGenerator> make_gi(int width, int height);

}  // namespace mcr::lfgen
