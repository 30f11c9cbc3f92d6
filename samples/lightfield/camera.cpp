#include "camera.h"

#include <algorithm>
#include <cmath>

namespace mcr::lfgen {

Camera Camera::look_at(int width, int height, const Vec3& eye, const Vec3& target, const Vec3& up,
                       double vfov_deg) {
  Camera c;
  c.width = width;
  c.height = height;
  c.eye = eye;
  c.forward = normalize(target - eye);
  c.right = normalize(cross(c.forward, up));
  c.down = cross(c.forward, c.right);
  c.focal_px = 0.5 * height / std::tan(0.5 * vfov_deg * M_PI / 180.0);
  return c;
}

Vec3 Camera::direction(double px, double py) const {
  return normalize(forward * focal_px + right * (px - 0.5 * width) + down * (py - 0.5 * height));
}

bool Camera::project(const Vec3& p, double& px, double& py) const {
  const Vec3 d = p - eye;
  const double z = dot(d, forward);
  if (z <= 0) return false;
  px = 0.5 * width + focal_px * dot(d, right) / z;
  py = 0.5 * height + focal_px * dot(d, down) / z;
  return true;
}

void Camera::screen_axis(const Vec3& p, const Vec3& d, double& ex, double& ey) const {
  const double eps = 1e-4 * std::max(1e-3, dot(p - eye, forward));
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  if (!project(p, x0, y0) || !project(p + d * eps, x1, y1)) {
    ex = ey = 0;
    return;
  }
  ex = (x1 - x0) / eps;
  ey = (y1 - y0) / eps;
}

void thin_lens_ray(const Camera& cam, double focus_m, double aperture_radius_m, double px, double py, double u1,
                   double u2, Vec3& org, Vec3& dir) {
  const Vec3 centre_dir = cam.direction(px, py);
  const Vec3 focus_point = cam.eye + centre_dir * (focus_m / dot(centre_dir, cam.forward));
  org = cam.eye + cam.right * (u1 * aperture_radius_m) + cam.down * (u2 * aperture_radius_m);
  dir = normalize(focus_point - org);
}

}  // namespace mcr::lfgen
