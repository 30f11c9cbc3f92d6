#include "gi.h"

#include <algorithm>
#include <cmath>

namespace mcr::lfgen {

namespace {
// v = R (a t + (1 - a) t^3), t = 2u - 1: a cubic with a linear part so that the density stays
// finite at 0; pdf per axis 1 / (2 R (a + 3 (1 - a) t^2)), centre/edge ratio (3 - 2a)/a = 28
// (gamma's marginal falls about 130x from 0 to 5).
constexpr double kLinear = 0.1;
double cubic(double u, double& pdf) {
  const double t = 2 * u - 1;
  pdf = 1 / (2 * kVRange * (kLinear + 3 * (1 - kLinear) * t * t));
  return kVRange * (kLinear * t + (1 - kLinear) * t * t * t);
}
}  // namespace

double v_gamma_integral(double a) {
  return 2 * a * std::acos(1 / (2 * a * a + 1)) / std::sqrt(1 + a * a);
}

void v_plane_sample(double u1, double u2, double& v1, double& v2, double& weight) {
  static const double C = v_gamma_integral(kVRange);
  double p1 = 0, p2 = 0;
  v1 = cubic(u1, p1);
  v2 = cubic(u2, p2);
  weight = v_gamma(v1, v2) / (p1 * p2) / C;
}

Vec3 Gi::reflected(const Hit& h) const {
  const Vec3 to_light = s_.light_pos - h.p;
  const double d = length(to_light);
  const Vec3 w = to_light / d;
  const double cos = dot(h.n, w);
  if (cos <= 0) return {};
  if (scene_.occluded(h.p + h.n * 1e-4, w, 0, d * (1 - 1e-4))) return {};
  return scene_.material(h.shape).at(h.p) * (s_.intensity * cos / (d * d) / M_PI);
}

void Gi::render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const {
  const Camera& cam = s_.camera;
  const Vec3 dir = cam.direction(x + 0.5, y + 0.5);
  Hit h;
  if (!scene_.intersect(cam.eye, dir, 0, 1e30, h)) {
    out.n = -dir;
    return;
  }
  out.p = h.p;
  out.n = h.n;
  out.depth = h.t;
  Vec3 t1, t2;
  tangent_frame(h.n, t1, t2);
  out.w1 = t1;
  out.w2 = t2;
  cam.screen_axis(h.p, t1, out.e1x, out.e1y);
  cam.screen_axis(h.p, t2, out.e2x, out.e2y);
  const Vec3 org = h.p + h.n * 1e-4;
  for (int j = 0; j < l; ++j)
    for (int i = 0; i < l; ++i) {
      const std::size_t k = std::size_t(i + l * j);
      double v1 = 0, v2 = 0, weight = 0;
      v_plane_sample((i + j1) / l, (j + j2) / l, v1, v2, weight);
      out.y1[k] = v1;
      out.y2[k] = v2;
      const Vec3 d = normalize(t1 * v1 + t2 * v2 + h.n);
      Hit r;
      if (!scene_.intersect(org, d, 0, 1e30, r)) continue;  // out through the open side: black
      out.value[k] = reflected(r) * weight;
      out.add_slope(dot(r.p - h.p, h.n));  // the reflector's distance along n, from the receiver itself
    }
}

std::unique_ptr<LightFieldGenerator> make_gi(int width, int height) {
  GiSetup s;
  s.camera = Camera::look_at(width, height, {0, -3.2, 1.5}, {0, 2, 1.3}, {0, 0, 1}, 48);
  s.light_pos = {0.3, 2.0, 2.0};
  s.intensity = 12;  // direct irradiance under it on the floor about pi: a white floor sends about 0.75
  auto g = std::make_unique<Gi>(s);
  Scene& sc = g->scene();
  Material white, red, green;
  white.albedo = {0.75, 0.75, 0.75};
  red.albedo = {0.75, 0.12, 0.1};
  green.albedo = {0.12, 0.6, 0.15};
  sc.add_quad({-2, -3.5, 0}, {4, 0, 0}, {0, 7.5, 0}, white);  // floor, out under the camera
  sc.add_quad({-2, 0, 3}, {4, 0, 0}, {0, 4, 0}, white);  // ceiling
  sc.add_quad({-2, 4, 0}, {4, 0, 0}, {0, 0, 3}, white);  // back wall
  sc.add_quad({-2, 0, 0}, {0, 4, 0}, {0, 0, 3}, red);    // left wall
  sc.add_quad({2, 0, 0}, {0, 4, 0}, {0, 0, 3}, green);   // right wall
  sc.add_box({-1.3, 2.2, 0}, {-0.5, 3.0, 1.6}, white);
  sc.add_sphere({0.8, 1.5, 0.5}, 0.5, white);
  g->commit();
  return g;
}

}  // namespace mcr::lfgen
