// Spheres (ellipsoids under a transform) and infinite planes as Embree user geometry, with
// exact analytic intersection in double precision.
#include <algorithm>
#include <cmath>

#include "worker/scene_geometry.hpp"
#include "worker/user_geometry.hpp"

namespace tessera {

namespace {

// The shape tests proper, inlined into the callbacks: true and the distance when the ray
// meets the shape with t_min < t < t_max.
[[gnu::always_inline]] inline bool sphere_distance(const PreparedSphere& sphere, const glm::vec3& origin,
                            const glm::vec3& direction, double t_min, double t_max, double& t) {
  Vec3 f;
  Vec3 d;
  double radius;
  if (sphere.world_sphere) {
    f = Vec3(origin) - sphere.world_center;
    d = Vec3(direction);
    radius = sphere.world_radius;
  } else {
    f = Vec3(sphere.world_to_object * glm::dvec4(Vec3(origin), 1.0)) - sphere.center;
    d = glm::dmat3(sphere.world_to_object) * Vec3(direction);
    radius = sphere.radius;
  }
  const double a = glm::dot(d, d);
  const double b = glm::dot(f, d);
  const double r2 = radius * radius;
  // Most rays that reach this test pass the sphere by: |f|²·a - b² = |q|²·a, q as below,
  // says so without a division. Cancellation makes it inexact, so it only rejects with a
  // margin far above its rounding error, and the exact test decides everything else.
  const double ff = glm::dot(f, f);
  if (ff * a - b * b > a * r2 + 1e-12 * ff * a) return false;
  // |q| is the distance from the centre to the ray's line; computing the discriminant from
  // it (instead of b² - ac) avoids cancellation for small spheres seen from far away.
  const Vec3 q = f - (b / a) * d;
  const double discriminant = a * (r2 - glm::dot(q, q));
  if (discriminant < 0.0) return false;
  const double c = ff - r2;
  const double h = -b - std::copysign(std::sqrt(discriminant), b);
  double t0 = c / h;
  double t1 = h / a;
  if (h == 0.0) t0 = t1 = 0.0;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 > t_min && t0 < t_max) {
    t = t0;
    return true;
  }
  if (t1 > t_min && t1 < t_max) {
    t = t1;
    return true;
  }
  return false;
}

[[gnu::always_inline]] inline bool plane_distance(const PreparedPlane& plane, const glm::vec3& origin,
                           const glm::vec3& direction, double t_min, double t_max, double& t) {
  const double denominator = glm::dot(Vec3(direction), plane.normal);
  const double numerator = plane.offset - glm::dot(Vec3(origin), plane.normal);
  // Most rays that miss a plane point away from it: the signs tell, without a division.
  if (t_min >= 0.0 && !(numerator > 0.0 ? denominator > 0.0 : numerator < 0.0 && denominator < 0.0))
    return false;
  if (denominator == 0.0) return false;
  t = numerator / denominator;
  return t > t_min && t < t_max;
}

}  // namespace

namespace {

// Planes are infinite; Embree needs finite boxes, so they get one far beyond any scene.
constexpr float kPlaneExtent = 1e18f;

// The nearest hit with t_min < t < t_max, and which primitive of the geometry it is on.
bool distance(const PreparedSphere& sphere, const glm::vec3& o, const glm::vec3& d, double t_min,
              double t_max, double& t, unsigned& primitive) {
  primitive = 0;
  return sphere_distance(sphere, o, d, t_min, t_max, t);
}

bool distance(const PlaneSet& set, const glm::vec3& o, const glm::vec3& d, double t_min,
              double t_max, double& t, unsigned& primitive) {
  bool found = false;
  for (unsigned i = 0; i < set.planes.size(); ++i) {
    double t_plane;
    if (!plane_distance(set.planes[i], o, d, t_min, t_max, t_plane)) continue;
    t = t_max = t_plane;  // nearer planes only from here on; on a tie the first one stays
    primitive = i;
    found = true;
  }
  return found;
}

// Embree hands over up to 16 rays at once. The tests of all of them run first, in a loop of
// their own, so that their divisions and square roots overlap instead of waiting on each
// other's branches; the hits are recorded after.
template <typename Shape>
void intersect_callback(const RTCIntersectFunctionNArguments* args) {
  const auto& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  const unsigned n = args->N;
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, n);
  auto* context = reinterpret_cast<HitContext*>(args->context);
  // Embree's packets hold at most 16 rays; chunks keep this right for any N all the same.
  for (unsigned base = 0; base < n; base += kPacketSize) {
    const unsigned end = std::min(n, base + kPacketSize);
    double t[kPacketSize];
    unsigned primitive[kPacketSize];
    bool found[kPacketSize];
    for (unsigned i = base; i < end; ++i) {
      found[i - base] = false;
      if (args->valid[i] != -1) continue;
      const glm::vec3 o(RTCRayN_org_x(ray, n, i), RTCRayN_org_y(ray, n, i),
                        RTCRayN_org_z(ray, n, i));
      const glm::vec3 d(RTCRayN_dir_x(ray, n, i), RTCRayN_dir_y(ray, n, i),
                        RTCRayN_dir_z(ray, n, i));
      found[i - base] = distance(shape, o, d, RTCRayN_tnear(ray, n, i), RTCRayN_tfar(ray, n, i),
                                 t[i - base], primitive[i - base]);
    }
    for (unsigned i = base; i < end; ++i) {
      if (!found[i - base]) continue;
      RTCRayN_tfar(ray, n, i) = static_cast<float>(t[i - base]);
      context->t[RTCRayN_id(ray, n, i)] = t[i - base];
      RTCHitN_u(hit, n, i) = 0.0f;
      RTCHitN_v(hit, n, i) = 0.0f;
      RTCHitN_primID(hit, n, i) = primitive[i - base];
      RTCHitN_geomID(hit, n, i) = args->geomID;
      RTCHitN_instID(hit, n, i, 0) = args->context->instID[0];
    }
  }
}

template <typename Shape>
void occluded_callback(const RTCOccludedFunctionNArguments* args) {
  const auto& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    const glm::vec3 o(RTCRayN_org_x(args->ray, n, i), RTCRayN_org_y(args->ray, n, i),
                      RTCRayN_org_z(args->ray, n, i));
    const glm::vec3 d(RTCRayN_dir_x(args->ray, n, i), RTCRayN_dir_y(args->ray, n, i),
                      RTCRayN_dir_z(args->ray, n, i));
    float& tfar = RTCRayN_tfar(args->ray, n, i);
    double t;
    unsigned primitive;
    if (distance(shape, o, d, RTCRayN_tnear(args->ray, n, i), tfar, t, primitive))
      tfar = -kInfinity;
  }
}

void plane_bounds(const RTCBoundsFunctionArguments* args) {
  *args->bounds_o = {-kPlaneExtent, -kPlaneExtent, -kPlaneExtent, 0.0f,
                     kPlaneExtent,  kPlaneExtent,  kPlaneExtent,  0.0f};
}

}  // namespace

namespace {

// The nearest plane on each lane with valid[i] == -1 of sixteen rays that start at t = 0,
// for any of Embree's ray layouts of sixteen.
template <typename Rays>
void nearest_of_planes(const PlaneSet& set, const Rays& rays, const int (&valid)[16],
                       double (&t)[16], int (&plane)[16]) {
  // In arrays of its own, so that the compiler need not allow for the outputs overlapping
  // the rays.
  double nearest[16];
  int index[16];
  for (int i = 0; i < 16; ++i) {
    nearest[i] = kInfinity;
    index[i] = -1;
  }
  // plane_distance() from t_min = 0 to the nearest plane so far, without its branches, so
  // that the sixteen lanes go two to an instruction. Its sign test only spares a division:
  // t > 0 holds exactly when numerator and denominator have one strict sign and the
  // quotient did not underflow, and a zero denominator gives an infinite or NaN t, which
  // fails t > 0 or t < nearest. So each lane gets plane_distance()'s very answer, the first
  // of equally near planes included.
  for (std::size_t p = 0; p < set.planes.size(); ++p) {
    const PreparedPlane& candidate = set.planes[p];
    for (int i = 0; i < 16; ++i) {
      const Vec3 origin(rays.org_x[i], rays.org_y[i], rays.org_z[i]);
      const Vec3 direction(rays.dir_x[i], rays.dir_y[i], rays.dir_z[i]);
      const double denominator = glm::dot(direction, candidate.normal);
      const double numerator = candidate.offset - glm::dot(origin, candidate.normal);
      const double t_plane = numerator / denominator;
      const bool nearer = (valid[i] == -1) & (t_plane > 0.0) & (t_plane < nearest[i]);
      nearest[i] = nearer ? t_plane : nearest[i];
      index[i] = nearer ? static_cast<int>(p) : index[i];
    }
  }
  std::copy(nearest, nearest + 16, t);
  std::copy(index, index + 16, plane);
}

}  // namespace

void planes_occlude(const PlaneSet& set, const RTCRay16& rays, const int (&valid)[16],
                    bool (&blocked)[16]) {
  // Some plane lies between 0 and tfar exactly when the nearest one does.
  double t[16];
  int plane[16];
  nearest_of_planes(set, rays, valid, t, plane);
  for (int i = 0; i < 16; ++i) blocked[i] = plane[i] >= 0 && t[i] < rays.tfar[i];
}

void nearest_planes(const PlaneSet& set, const RTCRayHit16& rayhit, const int (&valid)[16],
                    double (&t)[16], int (&plane)[16]) {
  nearest_of_planes(set, rayhit.ray, valid, t, plane);
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

void set_sphere_callbacks(RTCGeometry geometry) {
  rtcSetGeometryBoundsFunction(geometry, &sphere_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, &intersect_callback<PreparedSphere>);
  rtcSetGeometryOccludedFunction(geometry, &occluded_callback<PreparedSphere>);
}

void set_plane_callbacks(RTCGeometry geometry) {
  rtcSetGeometryBoundsFunction(geometry, &plane_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, &intersect_callback<PlaneSet>);
  rtcSetGeometryOccludedFunction(geometry, &occluded_callback<PlaneSet>);
}

}  // namespace tessera
