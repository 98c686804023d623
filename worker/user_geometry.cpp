// Spheres (ellipsoids under a transform) and infinite planes as Embree user geometry, with
// exact analytic intersection in double precision.
#include <algorithm>
#include <cmath>

#include "worker/scene_geometry.hpp"
#include "worker/user_geometry.hpp"

namespace tessera {

std::optional<double> intersect_sphere(const PreparedSphere& sphere, const glm::vec3& origin,
                                       const glm::vec3& direction, double t_min, double t_max) {
  const Vec3 o = Vec3(sphere.world_to_object * glm::dvec4(Vec3(origin), 1.0));
  const Vec3 d = glm::dmat3(sphere.world_to_object) * Vec3(direction);
  const Vec3 f = o - sphere.center;
  const double a = glm::dot(d, d);
  const double b = glm::dot(f, d);
  // |q| is the distance from the centre to the ray's line; computing the discriminant from
  // it (instead of b² - ac) avoids cancellation for small spheres seen from far away.
  const Vec3 q = f - (b / a) * d;
  const double r2 = sphere.radius * sphere.radius;
  const double discriminant = a * (r2 - glm::dot(q, q));
  if (discriminant < 0.0) return std::nullopt;
  const double c = glm::dot(f, f) - r2;
  const double h = -b - std::copysign(std::sqrt(discriminant), b);
  double t0 = c / h;
  double t1 = h / a;
  if (h == 0.0) t0 = t1 = 0.0;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 > t_min && t0 < t_max) return t0;
  if (t1 > t_min && t1 < t_max) return t1;
  return std::nullopt;
}

std::optional<double> intersect_plane(const PreparedPlane& plane, const glm::vec3& origin,
                                      const glm::vec3& direction, double t_min, double t_max) {
  const double denominator = glm::dot(Vec3(direction), plane.normal);
  if (denominator == 0.0) return std::nullopt;
  const double t = glm::dot(plane.point - Vec3(origin), plane.normal) / denominator;
  if (t > t_min && t < t_max) return t;
  return std::nullopt;
}

namespace {

// Planes are infinite; Embree needs finite boxes, so they get one far beyond any scene.
constexpr float kPlaneExtent = 1e18f;

template <typename Shape>
std::optional<double> intersect_any(const Shape& shape, const glm::vec3& o, const glm::vec3& d,
                                    double t_min, double t_max) {
  if constexpr (std::is_same_v<Shape, PreparedSphere>)
    return intersect_sphere(shape, o, d, t_min, t_max);
  else
    return intersect_plane(shape, o, d, t_min, t_max);
}

template <typename Shape>
void intersect_callback(const RTCIntersectFunctionNArguments* args) {
  const auto& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const glm::vec3 o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                      RTCRayN_org_z(ray, args->N, i));
    const glm::vec3 d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                      RTCRayN_dir_z(ray, args->N, i));
    float& tfar = RTCRayN_tfar(ray, args->N, i);
    const auto t = intersect_any(shape, o, d, RTCRayN_tnear(ray, args->N, i), tfar);
    if (!t) continue;
    tfar = static_cast<float>(*t);
    RTCHitN_u(hit, args->N, i) = 0.0f;
    RTCHitN_v(hit, args->N, i) = 0.0f;
    RTCHitN_primID(hit, args->N, i) = args->primID;
    RTCHitN_geomID(hit, args->N, i) = args->geomID;
    RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
  }
}

template <typename Shape>
void occluded_callback(const RTCOccludedFunctionNArguments* args) {
  const auto& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const glm::vec3 o(RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
                      RTCRayN_org_z(args->ray, args->N, i));
    const glm::vec3 d(RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
                      RTCRayN_dir_z(args->ray, args->N, i));
    float& tfar = RTCRayN_tfar(args->ray, args->N, i);
    if (intersect_any(shape, o, d, RTCRayN_tnear(args->ray, args->N, i), tfar)) tfar = -kInfinity;
  }
}

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const auto& sphere = *static_cast<const PreparedSphere*>(args->geometryUserPtr);
  // The transformed corners of the object-space cube bound the ellipsoid.
  Vec3 lo(std::numeric_limits<double>::max());
  Vec3 hi(std::numeric_limits<double>::lowest());
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 offset((corner & 1) ? 1.0 : -1.0, (corner & 2) ? 1.0 : -1.0,
                      (corner & 4) ? 1.0 : -1.0);
    const Vec3 p =
        Vec3(sphere.object_to_world * glm::dvec4(sphere.center + sphere.radius * offset, 1.0));
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  // Widen by a little so that rounding to float never cuts the surface off.
  const Vec3 pad = 1e-6 * (glm::abs(lo) + glm::abs(hi)) + 1e-9;
  lo -= pad;
  hi += pad;
  *args->bounds_o = {
      static_cast<float>(lo.x), static_cast<float>(lo.y), static_cast<float>(lo.z), 0.0f,
      static_cast<float>(hi.x), static_cast<float>(hi.y), static_cast<float>(hi.z), 0.0f};
}

void plane_bounds(const RTCBoundsFunctionArguments* args) {
  *args->bounds_o = {-kPlaneExtent, -kPlaneExtent, -kPlaneExtent, 0.0f,
                     kPlaneExtent,  kPlaneExtent,  kPlaneExtent,  0.0f};
}

}  // namespace

void set_sphere_callbacks(RTCGeometry geometry) {
  rtcSetGeometryBoundsFunction(geometry, &sphere_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, &intersect_callback<PreparedSphere>);
  rtcSetGeometryOccludedFunction(geometry, &occluded_callback<PreparedSphere>);
}

void set_plane_callbacks(RTCGeometry geometry) {
  rtcSetGeometryBoundsFunction(geometry, &plane_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, &intersect_callback<PreparedPlane>);
  rtcSetGeometryOccludedFunction(geometry, &occluded_callback<PreparedPlane>);
}

}  // namespace tessera
