#include "scene.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <limits>
#include <string>

#include "util/error.h"

namespace mcr::lfgen {

Vec3 Material::at(const Vec3& p) const {
  if (checker <= 0) return albedo;
  // Shifted by half a square so planes at whole multiples of the size do not sit on a seam.
  auto cell = [&](double v) { return long(std::floor(v / checker + 0.5)); };
  return ((cell(p.x) + cell(p.y) + cell(p.z)) & 1) ? albedo2 : albedo;
}

Scene::Scene() {
  device_ = rtcNewDevice(nullptr);
  if (!device_) throw Error(Errc::Internal, "Embree: cannot create a device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  scene_ = rtcNewScene(device_);
}

Scene::~Scene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

void Scene::add_triangles(const std::vector<Vec3>& vertices, const std::vector<unsigned>& indices, const Material& m) {
  RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), vertices.size()));
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    v[3 * i] = float(vertices[i].x);
    v[3 * i + 1] = float(vertices[i].y);
    v[3 * i + 2] = float(vertices[i].z);
  }
  auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), indices.size() / 3));
  for (std::size_t i = 0; i < indices.size(); ++i) idx[i] = indices[i];
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene_, g);
  rtcReleaseGeometry(g);
  if (materials_.size() <= id) materials_.resize(id + 1);
  materials_[id] = m;
}

void Scene::add_quad(const Vec3& c, const Vec3& u, const Vec3& v, const Material& m) {
  add_triangles({c, c + u, c + u + v, c + v}, {0, 1, 2, 0, 2, 3}, m);
}

void Scene::add_box(const Vec3& lo, const Vec3& hi, const Material& m) {
  std::vector<Vec3> p;
  for (int i = 0; i < 8; ++i) p.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
  // Two triangles per face; the winding does not matter (normals are turned to face the ray).
  add_triangles(p, {0, 1, 3, 0, 3, 2, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                    2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 3, 7, 1, 7, 5},
                m);
}

void Scene::add_sphere(const Vec3& c, double radius, const Material& m) {
  RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_SPHERE_POINT);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                        4 * sizeof(float), 1));
  v[0] = float(c.x);
  v[1] = float(c.y);
  v[2] = float(c.z);
  v[3] = float(radius);
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene_, g);
  rtcReleaseGeometry(g);
  if (materials_.size() <= id) materials_.resize(id + 1);
  materials_[id] = m;
}

void Scene::commit() {
  rtcCommitScene(scene_);
  const RTCError e = rtcGetDeviceError(device_);
  if (e != RTC_ERROR_NONE) throw Error(Errc::Internal, "Embree: building the scene failed (error " + std::to_string(int(e)) + ")");
}

namespace {
void set_ray(RTCRay& r, const Vec3& org, const Vec3& dir, double tmin, double tmax) {
  r.org_x = float(org.x);
  r.org_y = float(org.y);
  r.org_z = float(org.z);
  r.dir_x = float(dir.x);
  r.dir_y = float(dir.y);
  r.dir_z = float(dir.z);
  r.tnear = float(tmin);
  r.tfar = float(tmax);
  r.time = 0;
  r.mask = ~0u;
  r.id = 0;
  r.flags = 0;
}
}  // namespace

bool Scene::intersect(const Vec3& org, const Vec3& dir, double tmin, double tmax, Hit& hit) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  set_ray(rh.ray, org, dir, tmin, tmax);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit.t = rh.ray.tfar;
  hit.p = org + dir * hit.t;
  Vec3 n = normalize(Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
  hit.n = dot(n, dir) > 0 ? -n : n;
  hit.shape = rh.hit.geomID;
  return true;
}

bool Scene::occluded(const Vec3& org, const Vec3& dir, double tmin, double tmax) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  set_ray(r, org, dir, tmin, tmax);
  rtcOccluded1(scene_, &ctx, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

}  // namespace mcr::lfgen
