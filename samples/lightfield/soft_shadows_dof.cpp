#include "soft_shadows_dof.h"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <utility>
#include <vector>

namespace mcr::lfgen {

SoftShadowsDof::SoftShadowsDof(std::unique_ptr<SoftShadows> shadows, double focus_m, double aperture_radius_m)
    : shadows_(std::move(shadows)), focus_m_(focus_m), aperture_m_(aperture_radius_m) {}

void SoftShadowsDof::render_pixel(int x, int y, int l, double j1, double j2, PixelSamples& out) const {
  const Camera& cam = shadows_->setup().camera;
  const Scene& scene = shadows_->scene();
  const std::size_t spp = std::size_t(l) * std::size_t(l);
  out.u1.assign(spp, 0.0);
  out.u2.assign(spp, 0.0);
  out.texture.assign(spp, Vec3());
  const Vec3 centre_dir = cam.direction(x + 0.5, y + 0.5);
  Hit h;
  if (scene.intersect(cam.eye, centre_dir, 0, 1e30, h)) {
    out.p = h.p;
    out.n = h.n;
    out.depth = h.t;
    out.mod = shadows_->unoccluded(h, Vec3(1, 1, 1));  // the light alone: stage 1 shears it
    shadows_->receiver_axes(h, out);
  } else {
    out.n = -centre_dir;
  }
  // The light's strata: a shuffle of the l*l strata and a jitter of their own, hashed from the
  // pixel's lens jitter (24-bit fractions), so a seed still gives the same file on any thread count.
  unsigned long long key =
      mix64((static_cast<unsigned long long>(j1 * 16777216.0) << 24) ^ static_cast<unsigned long long>(j2 * 16777216.0));
  const double k1 = double(key >> 40) / 16777216.0, k2 = double((key >> 8) & 0xffffff) / 16777216.0;
  std::vector<std::size_t> light_stratum(spp);
  std::iota(light_stratum.begin(), light_stratum.end(), std::size_t(0));
  for (std::size_t i = spp; i > 1; --i) {
    key = mix64(key);
    std::swap(light_stratum[i - 1], light_stratum[std::size_t(key % i)]);
  }
  const double L = shadows_->y_range();
  const double per_inverse_depth = aperture_m_ * cam.focal_px;  // c = A focal_px (1/F - 1/z)
  for (int j = 0; j < l; ++j)
    for (int i = 0; i < l; ++i) {
      const std::size_t k = std::size_t(i + l * j);
      const double u1 = stratum(i, j1, l, 1.0), u2 = stratum(j, j2, l, 1.0);
      const int li = int(light_stratum[k] % std::size_t(l)), lj = int(light_stratum[k] / std::size_t(l));
      out.u1[k] = u1;
      out.u2[k] = u2;
      out.y1[k] = stratum(li, k1, l, L);
      out.y2[k] = stratum(lj, k2, l, L);
      Vec3 org, dir;
      thin_lens_ray(cam, focus_m_, aperture_m_, x + 0.5, y + 0.5, u1, u2, org, dir);
      Hit s;
      if (!scene.intersect(org, dir, 0, 1e30, s)) {
        out.add_lens_slope(-per_inverse_depth / focus_m_);  // nothing: black, at infinity
        continue;
      }
      out.add_lens_slope(-per_inverse_depth * (1 / focus_m_ - 1 / dot(s.p - cam.eye, cam.forward)));
      out.texture[k] = scene.material(s.shape).at(s.p);
      const SoftShadows::LightSample ls = shadows_->light_sample(s, out.y1[k], out.y2[k]);
      if (ls.occluded) out.add_slope(ls.slope);
      out.value[k] = out.texture[k] * ls.f;
    }
}

std::map<std::string, std::string> SoftShadowsDof::attributes() const {
  std::map<std::string, std::string> a = shadows_->attributes();
  std::ostringstream f, r;
  f << focus_m_;
  r << aperture_m_;
  a["mcrecon:focus_distance"] = f.str();
  a["mcrecon:lf_aperture_radius"] = r.str();
  return a;
}

std::unique_ptr<LightFieldGenerator> make_soft_shadows_dof(int width, int height) {
  return std::make_unique<SoftShadowsDof>(make_soft_shadows_scene(width, height, 0.5), 7.0, 0.35);
}

}  // namespace mcr::lfgen
