// Cylinders and cones as Embree user geometry, with exact analytic intersection in double
// precision, in the object frame where their axis is y. Each solid is the part of a ray
// that lies both inside its quadric (the side's tube, or the cone's double cone) and between
// its caps' planes, found the way the boxes' slab test finds its part: so a ray meeting the
// rim where the side and a cap meet is never let through a crack between them.
#include <cmath>
#include <limits>

#include "tracer/analytic_shapes.hpp"
#include "tracer/analytic_shapes_callbacks.hpp"
#include "tracer/scene_geometry.hpp"

namespace tessera {

using analytic_detail::Lanes;
using analytic_detail::set_callbacks;
using analytic_detail::transformed_bounds;

namespace {

constexpr double kEndless = std::numeric_limits<double>::infinity();

// Narrows [t_entry, t_exit], and the parts they lie on, to [enters, leaves]: box_root()'s
// step for one slab. Like it, the functions below have no branches, so that a loop of them
// over a packet's lanes vectorises and no lane waits on another's misprediction.
[[gnu::always_inline]] inline void narrow(double enters, unsigned enters_part, double leaves,
                                          unsigned leaves_part, double& t_entry,
                                          unsigned& entry_part, double& t_exit,
                                          unsigned& exit_part) {
  const bool later = enters > t_entry;
  t_entry = later ? enters : t_entry;
  entry_part = later ? enters_part : entry_part;
  const bool sooner = leaves < t_exit;
  t_exit = sooner ? leaves : t_exit;
  exit_part = sooner ? leaves_part : exit_part;
}

// The slab lo <= y <= hi across the axis, for the origin's y and the direction's, whose
// faces are the parts lo_part and hi_part. A zero dy gives infinite quotients, which keep
// the interval when the origin lies between the faces and empty it otherwise.
[[gnu::always_inline]] inline void narrow_to_slab(double fy, double dy, double lo, double hi,
                                                  unsigned lo_part, unsigned hi_part,
                                                  double& t_entry, unsigned& entry_part,
                                                  double& t_exit, unsigned& exit_part) {
  const double inverse = 1.0 / dy;
  const double t_lo = (lo - fy) * inverse;
  const double t_hi = (hi - fy) * inverse;
  // Forward along the axis the ray enters by the lo face and leaves by the hi one.
  const bool forward = t_lo < t_hi;
  narrow(forward ? t_lo : t_hi, forward ? lo_part : hi_part, forward ? t_hi : t_lo,
         forward ? hi_part : lo_part, t_entry, entry_part, t_exit, exit_part);
}

// The nearer of the interval's ends with t_min < t < t_max, as box_root() takes it.
[[gnu::always_inline]] inline bool first_end(double t_entry, unsigned entry_part, double t_exit,
                                             unsigned exit_part, double t_min, double t_max,
                                             double& t, unsigned& part) {
  const bool entry_in = (t_entry > t_min) & (t_entry < t_max);
  const bool exit_in = (t_exit > t_min) & (t_exit < t_max);
  t = entry_in ? t_entry : t_exit;
  part = entry_in ? entry_part : exit_part;
  return (t_entry <= t_exit) & (entry_in | exit_in);
}

// The roots of a t² + 2 b t + c in the stable form sphere_root() uses, given the
// discriminant b² - ac (from a cross product, which cancels less than b² - ac does): the
// nearer and the farther. Either may be infinite or NaN where a or the other factor is 0.
[[gnu::always_inline]] inline void roots(double a, double b, double c, double discriminant,
                                         double& nearer, double& farther) {
  const double h = -b - std::copysign(std::sqrt(discriminant), b);
  const double t0 = c / h;
  const double t1 = h / a;
  nearer = t0 > t1 ? t1 : t0;
  farther = t0 > t1 ? t0 : t1;
}

// The cylinder test, for f = origin - centre and the direction d in the object frame, the
// radius² r2 and half the height: whether the ray meets the solid with t_min < t < t_max,
// the nearer such t and its part.
[[gnu::always_inline]] inline bool cylinder_root(double fx, double fy, double fz, double dx,
                                                 double dy, double dz, double r2, double half,
                                                 double t_min, double t_max, double& t,
                                                 unsigned& part) {
  // The tube x² + z² <= r², in the plane across the axis.
  const double a = dx * dx + dz * dz;
  const double b = fx * dx + fz * dz;
  const double c = fx * fx + fz * fz - r2;
  const double g = fz * dx - fx * dz;  // (f × d).y
  const double discriminant = a * r2 - g * g;
  double nearer, farther;
  roots(a, b, c, discriminant, nearer, farther);
  // Along the axis (a = 0) the ray is inside the tube everywhere or nowhere.
  const bool across = a > 0.0;
  const bool meets = across ? discriminant >= 0.0 : c <= 0.0;
  double t_entry = !meets ? kEndless : across ? nearer : -kEndless;
  double t_exit = !meets ? -kEndless : across ? farther : kEndless;
  unsigned entry_part = kSide;
  unsigned exit_part = kSide;
  narrow_to_slab(fy, dy, -half, half, kBaseCap, kTopCap, t_entry, entry_part, t_exit, exit_part);
  return first_end(t_entry, entry_part, t_exit, exit_part, t_min, t_max, t, part);
}

// The cone test, for f = origin - apex and the direction d in the object frame: whether the
// ray meets the solid with t_min < t < t_max, the nearer such t and its part. The double
// cone x² + z² <= slope2 · y² has two nappes; the slab -height <= y <= 0 keeps the lower one,
// which the ray's part inside it must be found on.
[[gnu::always_inline]] inline bool cone_root(double fx, double fy, double fz, double dx, double dy,
                                             double dz, double slope2, double height, double t_min,
                                             double t_max, double& t, unsigned& part) {
  const double a = dx * dx + dz * dz - slope2 * (dy * dy);
  const double b = fx * dx + fz * dz - slope2 * (fy * dy);
  const double c = fx * fx + fz * fz - slope2 * (fy * fy);
  const double gx = fy * dz - fz * dy;
  const double gy = fz * dx - fx * dz;
  const double gz = fx * dy - fy * dx;
  const double discriminant = slope2 * (gx * gx + gz * gz) - gy * gy;
  // A ray steeper than the side (a < 0) meets both nappes, through the apex at worst, so
  // its discriminant is >= 0 but for rounding.
  const bool steep = a < 0.0;
  double nearer, farther;
  roots(a, b, c, steep & (discriminant < 0.0) ? 0.0 : discriminant, nearer, farther);
  // Shallower than the side (a > 0), the ray is inside between the roots. Steeper, it is
  // inside before the nearer root and after the farther one, and going down (dy < 0) the
  // part after is the lower nappe's; going up, the part before. Parallel to the side
  // (a = 0), the one finite root, c / h, bounds it the same way, should it lie on the lower
  // nappe; where it lies on the upper one, the ray never meets the lower.
  const bool down = dy < 0.0;
  const bool across = a > 0.0;
  const bool parallel = a == 0.0;
  const double bound = parallel ? c / (-b - std::copysign(std::sqrt(discriminant), b))
                       : down   ? farther
                                : nearer;
  const bool meets = across ? discriminant >= 0.0 : !parallel | (fy + bound * dy <= 0.0);
  double t_entry = !meets ? kEndless : across ? nearer : down ? bound : -kEndless;
  double t_exit = !meets ? -kEndless : across ? farther : down ? kEndless : bound;
  unsigned entry_part = kSide;
  unsigned exit_part = kSide;
  // The slab's top face meets the solid in the apex alone, which belongs to the side.
  narrow_to_slab(fy, dy, -height, 0.0, kBaseCap, kSide, t_entry, entry_part, t_exit, exit_part);
  return first_end(t_entry, entry_part, t_exit, exit_part, t_min, t_max, t, part);
}

// The nearest hit on each valid lane with tnear < t < tfar, and the part it is on, of a
// cylinder or a cone: `Root` (cylinder_root, cone_root) on the lane's ray in object space,
// relative to `anchor`, with the shape's two numbers `a` and `b`.
template <auto Root>
void axial_distances(const Mat4& world_to_object, const Vec3& anchor, double a, double b,
                     const Lanes& lanes, double (&t)[kPacketSize],
                     unsigned (&primitive)[kPacketSize], bool (&found)[kPacketSize]) {
  const std::size_t count = lanes.count;
  const glm::dmat4 to_object = world_to_object;
  const glm::dmat3 linear(to_object);
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 f =
        Vec3(to_object * glm::dvec4(lanes.org_x[i], lanes.org_y[i], lanes.org_z[i], 1.0)) - anchor;
    const Vec3 d = linear * Vec3(lanes.dir_x[i], lanes.dir_y[i], lanes.dir_z[i]);
    double root;
    unsigned part;
    const bool meets =
        Root(f.x, f.y, f.z, d.x, d.y, d.z, a, b, lanes.tnear[i], lanes.tfar[i], root, part);
    found[i] = (lanes.valid[i] == -1) & meets;
    t[i] = root;
    primitive[i] = part;
  }
}

void distances(const PreparedCylinder& cylinder, const Lanes& lanes, double (&t)[kPacketSize],
               unsigned (&primitive)[kPacketSize], bool (&found)[kPacketSize]) {
  axial_distances<cylinder_root>(cylinder.world_to_object, cylinder.center,
                                 cylinder.radius * cylinder.radius, cylinder.half_height, lanes, t,
                                 primitive, found);
}

void distances(const PreparedCone& cone, const Lanes& lanes, double (&t)[kPacketSize],
               unsigned (&primitive)[kPacketSize], bool (&found)[kPacketSize]) {
  axial_distances<cone_root>(cone.world_to_object, cone.apex, cone.slope2, cone.height, lanes, t,
                             primitive, found);
}

}  // namespace

void cylinder_bounds(const RTCBoundsFunctionArguments* args) {
  const auto& cylinder = *static_cast<const PreparedCylinder*>(args->geometryUserPtr);
  const Vec3 extent(cylinder.radius, cylinder.half_height, cylinder.radius);
  *args->bounds_o = transformed_bounds(cylinder.center - extent, cylinder.center + extent,
                                       cylinder.object_to_world);
}

void cone_bounds(const RTCBoundsFunctionArguments* args) {
  const auto& cone = *static_cast<const PreparedCone*>(args->geometryUserPtr);
  *args->bounds_o =
      transformed_bounds(cone.apex - Vec3(cone.radius, cone.height, cone.radius),
                         cone.apex + Vec3(cone.radius, 0.0, cone.radius), cone.object_to_world);
}

void set_cylinder_callbacks(RTCGeometry geometry) {
  set_callbacks<PreparedCylinder, distances>(geometry, &cylinder_bounds);
}

void set_cone_callbacks(RTCGeometry geometry) {
  set_callbacks<PreparedCone, distances>(geometry, &cone_bounds);
}

}  // namespace tessera
