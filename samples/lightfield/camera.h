#pragma once
// A pinhole camera through the lens centre; the thin lens of the dof scene adds an aperture
// on top of it (dof.cpp). Image coordinates are pixels, (0,0) the top-left corner, a pixel's
// centre at +0.5; `right` and `down` point along image +x and +y.
#include "vec3.h"

namespace mcr::lfgen {

struct Camera {
  int width = 0, height = 0;
  Vec3 eye, forward, right, down;  // orthonormal
  double focal_px = 1;             // lens centre to image plane, in pixels

  // Looking from eye at target, `up` roughly up, vertical field of view in degrees.
  static Camera look_at(int width, int height, const Vec3& eye, const Vec3& target, const Vec3& up,
                        double vfov_deg);
  // Unit direction from the lens centre through image point (px, py).
  Vec3 direction(double px, double py) const;
  // Image point of world point p through the lens centre; false behind the camera.
  bool project(const Vec3& p, double& px, double& py) const;
  // Pixels moved on screen per world unit that p moves along d: project p and p + eps d,
  // divide by eps (a finite difference of the projection, eps relative to p's depth).
  void screen_axis(const Vec3& p, const Vec3& d, double& ex, double& ey) const;
};

// The ray of image point (px, py) through a thin lens's point (u1, u2) (in units of the
// aperture radius, along the image's +x, +y): from that lens point to the image point's focus
// on the plane at camera depth focus_m (every ray of the image point passes through it).
void thin_lens_ray(const Camera& cam, double focus_m, double aperture_radius_m, double px, double py, double u1,
                   double u2, Vec3& org, Vec3& dir);

}  // namespace mcr::lfgen
