#include "dof.h"

#include <algorithm>
#include <cmath>

namespace mcr::lfgen {

double ThinLens::sensor_distance_m() const {
  const double f = lens_mm / 1000;
  return f * focus_m / (focus_m - f);
}

double ThinLens::image_shift_px(double z_m, int width) const {
  const double pitch = sensor_width_mm / 1000 / width;
  return aperture_radius_m() * sensor_distance_m() * (1 / focus_m - 1 / z_m) / pitch;
}

Dof::Dof(const DofSetup& setup) : s_(setup) {
  // The image plane sits at s_f behind the lens (not at f): the focus plane maps onto it.
  s_.camera.focal_px = s_.lens.sensor_distance_m() / (s_.lens.sensor_width_mm / 1000 / s_.camera.width);
}

Vec3 Dof::shade(const Hit& h) const {
  return scene_.material(h.shape).at(h.p) * (0.25 + 0.75 * std::max(0.0, dot(h.n, s_.light_dir)));
}

void Dof::lens_ray(double px, double py, double u1, double u2, Vec3& org, Vec3& dir) const {
  thin_lens_ray(s_.camera, s_.lens.focus_m, s_.lens.aperture_radius_m(), px, py, u1, u2, org, dir);
}

void Dof::render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const {
  const Camera& cam = s_.camera;
  const Vec3 centre_dir = cam.direction(x + 0.5, y + 0.5);
  const double per_inverse_depth = s_.lens.aperture_radius_m() * cam.focal_px;  // c = A focal_px (1/F - 1/z)
  Hit h;
  if (scene_.intersect(cam.eye, centre_dir, 0, 1e30, h)) {
    out.p = h.p;
    out.n = h.n;
    out.depth = h.t;
  } else {
    out.n = -centre_dir;
  }
  out.e1x = 1;
  out.e2y = 1;
  for (int j = 0; j < l; ++j)
    for (int i = 0; i < l; ++i) {
      const std::size_t k = std::size_t(i + l * j);
      const double u1 = stratum(i, j1, l, 1.0), u2 = stratum(j, j2, l, 1.0);
      out.y1[k] = u1;
      out.y2[k] = u2;
      Vec3 lens_point, dir;
      lens_ray(x + 0.5, y + 0.5, u1, u2, lens_point, dir);
      Hit s;
      if (!scene_.intersect(lens_point, dir, 0, 1e30, s)) {
        out.value[k] = s_.background;
        out.add_slope(-per_inverse_depth / s_.lens.focus_m);  // a background at infinity
        continue;
      }
      out.value[k] = shade(s);
      const double z = dot(s.p - cam.eye, cam.forward);
      out.add_slope(-per_inverse_depth * (1 / s_.lens.focus_m - 1 / z));
    }
}

std::map<std::string, std::string> Dof::attributes() const {
  // The names the sample sweep already reads for its circle of confusion.
  return {{"mcrecon:lens_mm", std::to_string(s_.lens.lens_mm)},
          {"mcrecon:fstop", std::to_string(s_.lens.fstop)},
          {"mcrecon:focus_distance", std::to_string(s_.lens.focus_m)},
          {"mcrecon:sensor_width_mm", std::to_string(s_.lens.sensor_width_mm)}};
}

std::unique_ptr<LightFieldGenerator> make_dof(int width, int height) {
  DofSetup s;
  s.camera = Camera::look_at(width, height, {0, -2.5, 0.35}, {0, 0, 0.22}, {0, 0, 1}, 30);
  s.lens.lens_mm = 85;
  s.lens.fstop = 1.2;
  s.lens.focus_m = 2.5;
  s.light_dir = normalize(Vec3(-0.4, -0.6, 0.7));
  s.background = {0.05, 0.05, 0.08};
  auto g = std::make_unique<Dof>(s);
  Scene& sc = g->scene();
  Material ground, wall, red, green, blue;
  ground.albedo = {0.8, 0.8, 0.75};
  ground.albedo2 = {0.15, 0.15, 0.2};
  ground.checker = 0.1;
  wall.albedo = {0.7, 0.7, 0.7};
  wall.albedo2 = {0.2, 0.3, 0.5};
  wall.checker = 0.25;
  red.albedo = {0.85, 0.2, 0.15};
  red.albedo2 = {0.9, 0.85, 0.8};
  red.checker = 0.03;
  green.albedo = {0.2, 0.7, 0.25};
  green.albedo2 = {0.9, 0.9, 0.85};
  green.checker = 0.06;
  blue.albedo = {0.2, 0.3, 0.85};
  blue.albedo2 = {0.9, 0.9, 0.85};
  blue.checker = 0.1;
  sc.add_quad({-4, -2, 0}, {8, 0, 0}, {0, 8, 0}, ground);
  sc.add_quad({-4, 5.5, 0}, {8, 0, 0}, {0, 0, 4}, wall);  // 8 m from the camera
  sc.add_sphere({-0.12, -1.3, 0.06}, 0.06, red);            // about 1.2 m: in front
  sc.add_sphere({0.05, 0, 0.15}, 0.15, green);              // 2.5 m: in focus
  sc.add_sphere({0.5, 2.5, 0.3}, 0.3, blue);                // 5 m: behind
  g->commit();
  return g;
}

}  // namespace mcr::lfgen
