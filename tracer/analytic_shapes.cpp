// Spheres (ellipsoids under a transform), boxes and infinite planes as Embree user
// geometry, with exact analytic intersection in double precision. The planes' tests outside
// Embree are in analytic_shapes_planes.cpp, cylinders and cones in
// analytic_shapes_quadrics.cpp, and the callbacks all of them share in
// analytic_shapes_callbacks.hpp.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "tracer/analytic_shapes.hpp"
#include "tracer/analytic_shapes_callbacks.hpp"
#include "tracer/scene_geometry.hpp"

namespace tessera {

using analytic_detail::Lanes;
using analytic_detail::set_callbacks;
using analytic_detail::transformed_bounds;

namespace {

// The sphere test proper, for f = origin - centre and the direction d, both in the frame
// where the shape is a sphere of radius² r2: whether the ray meets it with
// t_min < t < t_max, and the nearer such t. It has no branches, so that a loop of these
// over a packet's lanes vectorises (two lanes to an SSE2 instruction) and no lane waits
// on another's mispredicted rejection. It takes and gives scalars: GCC does not vectorise
// a loop through glm's vectors, nor one through a returned struct. The sums go in
// glm::dot's order, (x + y) + z.
[[gnu::always_inline]] inline bool sphere_root(double fx, double fy, double fz, double dx,
                                               double dy, double dz, double r2, double t_min,
                                               double t_max, double& t) {
  const double a = dx * dx + dy * dy + dz * dz;
  const double b = fx * dx + fy * dy + fz * dz;
  // Most rays that reach this test pass the sphere by: |f|²·a - b² = |q|²·a, q as below,
  // says so without a division. Cancellation makes it inexact, so it only rejects with a
  // margin far above its rounding error, and the exact test decides everything else.
  const double ff = fx * fx + fy * fy + fz * fz;
  const bool passes_by = ff * a - b * b > a * r2 + 1e-12 * ff * a;
  // |q| is the distance from the centre to the ray's line; computing the discriminant from
  // it (instead of b² - ac) avoids cancellation for small spheres seen from far away.
  const double s = b / a;
  const double qx = fx - s * dx;
  const double qy = fy - s * dy;
  const double qz = fz - s * dz;
  const double discriminant = a * (r2 - (qx * qx + qy * qy + qz * qz));
  const double c = ff - r2;
  const double h = -b - std::copysign(std::sqrt(discriminant), b);
  // Where h = 0 (a ray tangent to the sphere at its own origin) the roots are ±infinity or
  // NaN and ±0; t_min >= 0, as Embree requires, so neither is taken, and the divisions need
  // no branch around them.
  const double t0 = c / h;
  const double t1 = h / a;
  const double nearer = t0 > t1 ? t1 : t0;
  const double farther = t0 > t1 ? t0 : t1;
  const bool nearer_in = (nearer > t_min) & (nearer < t_max);
  const bool farther_in = (farther > t_min) & (farther < t_max);
  t = nearer_in ? nearer : farther;
  return !passes_by & !(discriminant < 0.0) & (nearer_in | farther_in);
}

// The slab test, for the origin o and direction d in the frame where the box spans lo to
// hi: whether the ray meets it with t_min < t < t_max, the nearer such t and its face. Like
// sphere_root(), it has no branches. A zero direction component gives infinite quotients,
// which leave the interval as it is when the origin lies within that slab and empty it
// otherwise; an origin exactly on such a slab's face gives NaN, which empties it too.
[[gnu::always_inline]] inline bool box_root(const double (&o)[3], const double (&d)[3],
                                            const Vec3& lo, const Vec3& hi, double t_min,
                                            double t_max, double& t, unsigned& face) {
  double t_entry = -std::numeric_limits<double>::infinity();
  double t_exit = std::numeric_limits<double>::infinity();
  unsigned entry_face = 0;
  unsigned exit_face = 0;
  for (unsigned axis = 0; axis < 3; ++axis) {
    const double inverse = 1.0 / d[axis];
    const double t_lo = (lo[axis] - o[axis]) * inverse;
    const double t_hi = (hi[axis] - o[axis]) * inverse;
    // Forward along the axis the ray enters by the lo face and leaves by the hi one.
    const bool forward = t_lo < t_hi;
    const double enters = forward ? t_lo : t_hi;
    const double leaves = forward ? t_hi : t_lo;
    const bool later = enters > t_entry;
    t_entry = later ? enters : t_entry;
    entry_face = later ? 2 * axis + !forward : entry_face;
    const bool sooner = leaves < t_exit;
    t_exit = sooner ? leaves : t_exit;
    exit_face = sooner ? 2 * axis + forward : exit_face;
  }
  const bool entry_in = (t_entry > t_min) & (t_entry < t_max);
  const bool exit_in = (t_exit > t_min) & (t_exit < t_max);
  t = entry_in ? t_entry : t_exit;
  face = entry_in ? entry_face : exit_face;
  return (t_entry <= t_exit) & (entry_in | exit_in);
}

[[gnu::always_inline]] inline bool plane_distance(const PreparedPlane& plane,
                                                  const glm::vec3& origin,
                                                  const glm::vec3& direction, double t_min,
                                                  double t_max, double& t) {
  const double denominator = glm::dot(Vec3(direction), plane.normal);
  const double numerator = plane.offset - glm::dot(Vec3(origin), plane.normal);
  // Most rays that miss a plane point away from it: the signs tell, without a division.
  if (t_min >= 0.0 && !(numerator > 0.0 ? denominator > 0.0 : numerator < 0.0 && denominator < 0.0))
    return false;
  if (denominator == 0.0) return false;
  t = numerator / denominator;
  return t > t_min && t < t_max;
}

// Planes are infinite; Embree needs finite boxes, so they get one far beyond any scene.
constexpr float kPlaneExtent = 1e18f;

// The nearest hit on each valid lane with tnear < t < tfar, and which primitive of the
// geometry it is on: found[i] says whether t[i] and primitive[i] hold one.
void distances(const PreparedSphere& sphere, const Lanes& lanes, double (&t)[kPacketSize],
               unsigned (&primitive)[kPacketSize], bool (&found)[kPacketSize]) {
  // Plain locals, which GCC can keep in registers across the loop's stores.
  const std::size_t count = lanes.count;
  const int* valid = lanes.valid;
  const float *org_x = lanes.org_x, *org_y = lanes.org_y, *org_z = lanes.org_z;
  const float *dir_x = lanes.dir_x, *dir_y = lanes.dir_y, *dir_z = lanes.dir_z;
  const float *tnear = lanes.tnear, *tfar = lanes.tfar;
  for (std::size_t i = 0; i < count; ++i) primitive[i] = 0;
  const bool in_world = sphere.world_sphere;
  const Vec3 center = in_world ? sphere.world_center : sphere.center;
  const double radius = in_world ? sphere.world_radius : sphere.radius;
  const double r2 = radius * radius;
  if (in_world) {
    for (std::size_t i = 0; i < count; ++i) {
      double root;
      const bool meets = sphere_root(org_x[i] - center.x, org_y[i] - center.y, org_z[i] - center.z,
                                     dir_x[i], dir_y[i], dir_z[i], r2, tnear[i], tfar[i], root);
      found[i] = (valid[i] == -1) & meets;
      t[i] = root;
    }
    return;
  }
  const glm::dmat4 to_object = sphere.world_to_object;
  const glm::dmat3 linear(to_object);
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 f = Vec3(to_object * glm::dvec4(org_x[i], org_y[i], org_z[i], 1.0)) - center;
    const Vec3 d = linear * Vec3(dir_x[i], dir_y[i], dir_z[i]);
    double root;
    const bool meets = sphere_root(f.x, f.y, f.z, d.x, d.y, d.z, r2, tnear[i], tfar[i], root);
    found[i] = (valid[i] == -1) & meets;
    t[i] = root;
  }
}

// One lane of a box's test, in the box's frame: o and d are the lane's ray there.
[[gnu::always_inline]] inline void box_lane(const Vec3& lo, const Vec3& hi, const Lanes& lanes,
                                            std::size_t i, const double (&o)[3],
                                            const double (&d)[3], double (&t)[kPacketSize],
                                            unsigned (&primitive)[kPacketSize],
                                            bool (&found)[kPacketSize]) {
  double root;
  unsigned face;
  const bool meets = box_root(o, d, lo, hi, lanes.tnear[i], lanes.tfar[i], root, face);
  found[i] = (lanes.valid[i] == -1) & meets;
  t[i] = root;
  primitive[i] = face;
}

void distances(const PreparedBox& box, const Lanes& lanes, double (&t)[kPacketSize],
               unsigned (&primitive)[kPacketSize], bool (&found)[kPacketSize]) {
  const std::size_t count = lanes.count;
  const Vec3 lo = box.lo;
  const Vec3 hi = box.hi;
  // Two loops, so that the common one has no matrix product per lane.
  if (box.world_box) {
    for (std::size_t i = 0; i < count; ++i) {
      const double o[3] = {lanes.org_x[i], lanes.org_y[i], lanes.org_z[i]};
      const double d[3] = {lanes.dir_x[i], lanes.dir_y[i], lanes.dir_z[i]};
      box_lane(lo, hi, lanes, i, o, d, t, primitive, found);
    }
    return;
  }
  const glm::dmat4 to_object = box.world_to_object;
  const glm::dmat3 linear(to_object);
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 f =
        Vec3(to_object * glm::dvec4(lanes.org_x[i], lanes.org_y[i], lanes.org_z[i], 1.0));
    const Vec3 g = linear * Vec3(lanes.dir_x[i], lanes.dir_y[i], lanes.dir_z[i]);
    const double o[3] = {f.x, f.y, f.z};
    const double d[3] = {g.x, g.y, g.z};
    box_lane(lo, hi, lanes, i, o, d, t, primitive, found);
  }
}

void distances(const PlaneSet& set, const Lanes& lanes, double (&t)[kPacketSize],
               unsigned (&primitive)[kPacketSize], bool (&found)[kPacketSize]) {
  for (std::size_t i = 0; i < lanes.count; ++i) {
    found[i] = false;
    if (lanes.valid[i] != -1) continue;
    const glm::vec3 o(lanes.org_x[i], lanes.org_y[i], lanes.org_z[i]);
    const glm::vec3 d(lanes.dir_x[i], lanes.dir_y[i], lanes.dir_z[i]);
    double t_max = lanes.tfar[i];
    for (unsigned p = 0; p < set.planes.size(); ++p) {
      double t_plane;
      if (!plane_distance(set.planes[p], o, d, lanes.tnear[i], t_max, t_plane)) continue;
      t[i] = t_max = t_plane;  // nearer planes only from here on; on a tie the first one stays
      primitive[i] = p;
      found[i] = true;
    }
  }
}

void plane_bounds(const RTCBoundsFunctionArguments* args) {
  *args->bounds_o = {-kPlaneExtent, -kPlaneExtent, -kPlaneExtent, 0.0f,
                     kPlaneExtent,  kPlaneExtent,  kPlaneExtent,  0.0f};
}

}  // namespace

RTCBounds analytic_detail::transformed_bounds(const Vec3& box_lo, const Vec3& box_hi,
                                              const Mat4& transform) {
  Vec3 lo(std::numeric_limits<double>::max());
  Vec3 hi(std::numeric_limits<double>::lowest());
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p(transform * glm::dvec4((corner & 1) ? box_hi.x : box_lo.x,
                                        (corner & 2) ? box_hi.y : box_lo.y,
                                        (corner & 4) ? box_hi.z : box_lo.z, 1.0));
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  // Widen by a little so that rounding to float never cuts the surface off.
  const Vec3 pad = 1e-6 * (glm::abs(lo) + glm::abs(hi)) + 1e-9;
  lo -= pad;
  hi += pad;
  return {static_cast<float>(lo.x), static_cast<float>(lo.y), static_cast<float>(lo.z), 0.0f,
          static_cast<float>(hi.x), static_cast<float>(hi.y), static_cast<float>(hi.z), 0.0f};
}

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const auto& sphere = *static_cast<const PreparedSphere*>(args->geometryUserPtr);
  // The transformed corners of the object-space cube bound the ellipsoid.
  *args->bounds_o = transformed_bounds(sphere.center - sphere.radius, sphere.center + sphere.radius,
                                       sphere.object_to_world);
}

void box_bounds(const RTCBoundsFunctionArguments* args) {
  const auto& box = *static_cast<const PreparedBox*>(args->geometryUserPtr);
  *args->bounds_o =
      transformed_bounds(box.lo, box.hi, box.world_box ? Mat4(1.0) : box.object_to_world);
}

void set_sphere_callbacks(RTCGeometry geometry) {
  set_callbacks<PreparedSphere, distances>(geometry, &sphere_bounds);
}

void set_box_callbacks(RTCGeometry geometry) {
  set_callbacks<PreparedBox, distances>(geometry, &box_bounds);
}

void set_plane_callbacks(RTCGeometry geometry) {
  set_callbacks<PlaneSet, distances>(geometry, &plane_bounds);
}

}  // namespace tessera
