#pragma once
// The geometry of a light-field scene in Embree 3: parallelograms and boxes as triangles,
// spheres as Embree's native sphere points, one diffuse material per shape. Read-only and
// safe to trace from many threads once committed.
#include <vector>

#include "vec3.h"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace mcr::lfgen {

struct Material {
  Vec3 albedo{0.7, 0.7, 0.7};
  Vec3 albedo2{0.7, 0.7, 0.7};  // the checker's other colour
  double checker = 0;           // solid 3D checker square size in world units; 0 = plain
  Vec3 at(const Vec3& p) const;
};

struct Hit {
  double t = 0;
  Vec3 p, n;  // n unit, turned to face the ray
  unsigned shape = 0;
};

class Scene {
 public:
  Scene();
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  void add_quad(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v, const Material& m);
  void add_box(const Vec3& lo, const Vec3& hi, const Material& m);  // axis-aligned
  void add_sphere(const Vec3& centre, double radius, const Material& m);
  void commit();  // before any trace; throws Error(Internal) when Embree fails

  // Closest hit along org + t dir, t in (tmin, tmax), dir unit.
  bool intersect(const Vec3& org, const Vec3& dir, double tmin, double tmax, Hit& hit) const;
  bool occluded(const Vec3& org, const Vec3& dir, double tmin, double tmax) const;
  const Material& material(unsigned shape) const { return materials_[shape]; }

 private:
  void add_triangles(const std::vector<Vec3>& vertices, const std::vector<unsigned>& indices, const Material& m);
  RTCDeviceTy* device_ = nullptr;
  RTCSceneTy* scene_ = nullptr;
  std::vector<Material> materials_;  // by Embree geometry id
};

}  // namespace mcr::lfgen
