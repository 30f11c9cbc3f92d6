#include "soft_shadows.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace mcr::lfgen {

SoftShadows::LightSample SoftShadows::light_sample(const Hit& h, double u1, double u2) const {
  LightSample r;
  const Vec3 nl = cross(s_.a1, s_.a2);
  const Vec3 yw = s_.light_centre + s_.a1 * u1 + s_.a2 * u2;
  const Vec3 to_light = yw - h.p;
  const double d1 = length(to_light);
  const Vec3 w = to_light / d1;
  const double cos_r = dot(h.n, w), cos_l = -dot(nl, w);
  if (cos_r <= 0 || cos_l <= 0) return r;  // no light either way: f = 0, no occluder to see
  // From the light point towards the receiver: the closest hit is the first occluder.
  Hit occ;
  if (scene_.intersect(yw, -w, 0, d1 * (1 - 1e-4), occ)) {
    r.occluded = true;
    r.slope = d1 / occ.t - 1;
    return r;
  }
  r.f = s_.radiance / M_PI * cos_r * cos_l / (d1 * d1);
  return r;
}

Vec3 SoftShadows::unoccluded(const Hit& h, const Vec3& texture) const {
  const Vec3 nl = cross(s_.a1, s_.a2);
  const double L = s_.half_side;
  const int g = 16;
  const double sigma = sigma_y();
  Vec3 sum;
  double wsum = 0;
  for (int j = 0; j < g; ++j)
    for (int i = 0; i < g; ++i) {
      const double u1 = -L + (i + 0.5) * 2 * L / g, u2 = -L + (j + 0.5) * 2 * L / g;
      const double wg = std::exp(-(u1 * u1 + u2 * u2) / (2 * sigma * sigma));
      wsum += wg;
      const Vec3 to_light = s_.light_centre + s_.a1 * u1 + s_.a2 * u2 - h.p;
      const double d1 = length(to_light);
      const Vec3 w = to_light / d1;
      const double cos_r = dot(h.n, w), cos_l = -dot(nl, w);
      if (cos_r > 0 && cos_l > 0) sum = sum + texture * (wg * s_.radiance / M_PI * cos_r * cos_l / (d1 * d1));
    }
  return sum / wsum;
}

void SoftShadows::receiver_axes(const Hit& h, PixelSamples& out) const {
  // x_i: the receiver displacement in its tangent plane that moves one unit along a_i when
  // projected along the light normal: a_i + t nl with (a_i + t nl) . n = 0. A receiver nearly
  // perpendicular to the light has no such finite displacement: the cosine is held at 0.1.
  const Vec3 nl = cross(s_.a1, s_.a2);
  double nn = dot(nl, h.n);
  if (std::fabs(nn) < 0.1) nn = nn < 0 ? -0.1 : 0.1;
  const Vec3 x1 = s_.a1 - nl * (dot(s_.a1, h.n) / nn), x2 = s_.a2 - nl * (dot(s_.a2, h.n) / nn);
  out.w1 = s_.a1;  // x1 . a1 = 1, x2 . a1 = 0: D . a_i is D's x_i for D in the tangent plane
  out.w2 = s_.a2;
  s_.camera.screen_axis(h.p, x1, out.e1x, out.e1y);
  s_.camera.screen_axis(h.p, x2, out.e2x, out.e2y);
}

void SoftShadows::render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const {
  const Camera& cam = s_.camera;
  const Vec3 dir = cam.direction(x + 0.5, y + 0.5);
  Hit h;
  if (!scene_.intersect(cam.eye, dir, 0, 1e30, h)) {
    out.n = -dir;  // nothing seen: black, no slopes, no axes
    return;
  }
  out.p = h.p;
  out.n = h.n;
  out.depth = h.t;
  const Vec3 albedo = scene_.material(h.shape).at(h.p);
  const double L = s_.half_side;
  for (int j = 0; j < l; ++j)
    for (int i = 0; i < l; ++i) {
      const std::size_t k = std::size_t(i + l * j);
      const double u1 = stratum(i, j1, l, L), u2 = stratum(j, j2, l, L);
      out.y1[k] = u1;
      out.y2[k] = u2;
      const LightSample ls = light_sample(h, u1, u2);
      if (ls.occluded) out.add_slope(ls.slope);
      else if (ls.f != 0) out.value[k] = albedo * ls.f;
    }
  // The modulation: the same light with nothing in the way, what the filters multiply the
  // sheared visibility by.
  out.mod = unoccluded(h, albedo);
  receiver_axes(h, out);
}

std::map<std::string, std::string> SoftShadows::attributes() const {
  auto v3 = [](const Vec3& v) {
    std::ostringstream s;
    s << v.x << ' ' << v.y << ' ' << v.z;
    return s.str();
  };
  return {{"mcrecon:lf_light_centre", v3(s_.light_centre)},
          {"mcrecon:lf_light_a1", v3(s_.a1)},
          {"mcrecon:lf_light_a2", v3(s_.a2)}};
}

std::unique_ptr<LightFieldGenerator> make_soft_shadows(int width, int height) {
  return make_soft_shadows_scene(width, height);
}

std::unique_ptr<SoftShadows> make_soft_shadows_scene(int width, int height, double ground_checker) {
  SoftShadowsSetup s;
  s.camera = Camera::look_at(width, height, {0, -6.5, 4.5}, {0, -0.2, 0.4}, {0, 0, 1}, 45);
  const double H = 4, turn = 20 * M_PI / 180;
  s.light_centre = {0, 0, H};
  s.a1 = {std::cos(turn), std::sin(turn), 0};
  s.a2 = {std::sin(turn), -std::cos(turn), 0};  // a1 x a2 = (0, 0, -1): emits downwards
  s.half_side = 0.6;
  s.radiance = M_PI * H * H;  // unoccluded ground right under the light: f = albedo
  auto g = std::make_unique<SoftShadows>(s);
  Scene& sc = g->scene();
  Material ground;
  ground.albedo = {0.8, 0.8, 0.8};
  ground.albedo2 = {0.35, 0.3, 0.25};
  ground.checker = ground_checker;
  sc.add_quad({-40, -40, 0}, {80, 0, 0}, {0, 80, 0}, ground);  // fills the view to the top
  Material red, blue, yellow;
  red.albedo = {0.8, 0.25, 0.2};
  blue.albedo = {0.25, 0.35, 0.8};
  yellow.albedo = {0.8, 0.7, 0.2};
  sc.add_sphere({-1.3, 0.5, 1.1}, 0.5, red);                // d2 about 2.4 to 3.4
  sc.add_box({-0.1, 0.8, 1.7}, {1.9, 0.92, 1.78}, yellow);  // thin bar high up: wide penumbra
  sc.add_box({0.5, -1.7, 0}, {1.3, -0.9, 0.7}, blue);       // on the ground: contact shadow
  g->commit();
  return g;
}

}  // namespace mcr::lfgen
