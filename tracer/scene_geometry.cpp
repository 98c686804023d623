// SceneGeometry's queries for single rays, and the hits rebuilt in double by finish_hit(),
// which the packets' queries (scene_geometry_packet.cpp) call too for the shapes they do not
// rebuild on all lanes at once.
#include "tracer/scene_geometry.hpp"

#include <algorithm>
#include <cmath>

#include "tracer/analytic_shapes.hpp"
#include "tracer/mesh_bvh.hpp"

namespace tessera {
namespace {

using geometry_detail::across_axis;
using geometry_detail::plane_hit;
using geometry_detail::world_sphere_hit;

struct TriangleHit {
  double t, u, v;
};

// Möller–Trumbore in double: recomputes the hit Embree found, from the ray's floats (or,
// on a placed mesh, from them taken into object space).
std::optional<TriangleHit> intersect_triangle(const Vec3& v0, const Vec3& v1, const Vec3& v2,
                                              const Vec3& o, const Vec3& d) {
  const Vec3 e1 = v1 - v0;
  const Vec3 e2 = v2 - v0;
  const Vec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (det == 0.0) return std::nullopt;
  const double inv = 1.0 / det;
  const Vec3 s = o - v0;
  const Vec3 q = glm::cross(s, e1);
  return TriangleHit{glm::dot(e2, q) * inv, glm::dot(s, p) * inv, glm::dot(d, q) * inv};
}

// finish_hit() for each kind of shape: `exact_t` is the callback's distance.

void finish_sphere_hit(const Ray& ray, const PreparedSphere& sphere, double exact_t,
                       SurfaceHit& hit) {
  hit.t = exact_t;
  if (sphere.world_sphere) {
    double n[3];
    double p[3];
    world_sphere_hit(ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y,
                     ray.direction.z, hit.t, sphere.world_center.x, sphere.world_center.y,
                     sphere.world_center.z, sphere.world_radius, n, p);
    hit.position = Vec3(p[0], p[1], p[2]);
    hit.normal = Vec3(n[0], n[1], n[2]);
    hit.shading_normal = hit.normal;
    return;
  }
  const Vec3 o = Vec3(sphere.world_to_object * glm::dvec4(Vec3(ray.origin), 1.0));
  const Vec3 d = glm::dmat3(sphere.world_to_object) * Vec3(ray.direction);
  const Vec3 n = glm::normalize(o + hit.t * d - sphere.center);
  // Snapping the point onto the surface removes the error that o + t·d accumulates.
  hit.position = Vec3(sphere.object_to_world * glm::dvec4(sphere.center + sphere.radius * n, 1.0));
  hit.normal = glm::normalize(glm::transpose(glm::dmat3(sphere.world_to_object)) * n);
  hit.shading_normal = hit.normal;
}

void finish_box_hit(const Ray& ray, const PreparedBox& box, unsigned face, double exact_t,
                    SurfaceHit& hit) {
  hit.t = exact_t;
  Vec3 o(ray.origin);
  Vec3 d(ray.direction);
  if (!box.world_box) {
    o = Vec3(box.world_to_object * glm::dvec4(o, 1.0));
    d = glm::dmat3(box.world_to_object) * d;
  }
  // Snapping the point onto its face removes the error that o + t·d accumulates.
  Vec3 p = glm::clamp(o + hit.t * d, box.lo, box.hi);
  const unsigned axis = face / 2;
  p[axis] = face % 2 == 1 ? box.hi[axis] : box.lo[axis];
  hit.position = box.world_box ? p : Vec3(box.object_to_world * glm::dvec4(p, 1.0));
  hit.normal = box.face_normals[face];
  hit.shading_normal = hit.normal;
}

// The frame where a cylinder's or a cone's axis is y, and the object-space point o + t·d
// there relative to `anchor` (a cylinder's centre, a cone's apex).
Vec3 object_point(const Ray& ray, const Mat4& world_to_object, const Vec3& anchor, double t) {
  const Vec3 o = Vec3(world_to_object * glm::dvec4(Vec3(ray.origin), 1.0));
  const Vec3 d = glm::dmat3(world_to_object) * Vec3(ray.direction);
  return o + t * d - anchor;
}

// A point on a cap at height y, of radius `radius`: o + t·d snapped onto its plane, and
// into its disc should rounding have taken it past the rim.
Vec3 cap_point(const Vec3& p, double y, double radius) {
  double distance, ux, uz;
  across_axis(p, distance, ux, uz);
  if (distance <= radius) return Vec3(p.x, y, p.z);
  return Vec3(radius * ux, y, radius * uz);
}

// A hit of a cylinder or a cone, from its object-space point and outward normal.
void finish_axial_hit(const Vec3& point, const Vec3& normal, const Mat4& object_to_world,
                      const glm::dmat3& normal_matrix, SurfaceHit& hit) {
  hit.position = Vec3(object_to_world * glm::dvec4(point, 1.0));
  hit.normal = glm::normalize(normal_matrix * normal);
  hit.shading_normal = hit.normal;
}

void finish_cylinder_hit(const Ray& ray, const PreparedCylinder& cylinder, unsigned part,
                         double exact_t, SurfaceHit& hit) {
  hit.t = exact_t;
  const Vec3 p = object_point(ray, cylinder.world_to_object, cylinder.center, exact_t);
  const double half = cylinder.half_height;
  // Snapping the point onto its part removes the error that o + t·d accumulates.
  Vec3 snapped;
  Vec3 normal(0.0);
  if (part == kSide) {
    double distance, ux, uz;
    across_axis(p, distance, ux, uz);
    snapped = Vec3(cylinder.radius * ux, std::clamp(p.y, -half, half), cylinder.radius * uz);
    // On the axis only through rounding gone wild; a unit normal keeps the pixel finite.
    normal = distance > 0.0 ? Vec3(ux, 0.0, uz) : Vec3(1.0, 0.0, 0.0);
  } else {
    const double side = part == kTopCap ? 1.0 : -1.0;
    snapped = cap_point(p, side * half, cylinder.radius);
    normal.y = side;
  }
  finish_axial_hit(cylinder.center + snapped, normal, cylinder.object_to_world,
                   cylinder.normal_matrix, hit);
}

void finish_cone_hit(const Ray& ray, const PreparedCone& cone, unsigned part, double exact_t,
                     SurfaceHit& hit) {
  hit.t = exact_t;
  const Vec3 p = object_point(ray, cone.world_to_object, cone.apex, exact_t);
  Vec3 snapped;
  Vec3 normal;
  if (part == kSide) {
    // Across the axis, the side is the segment from the apex (0, 0) to the rim (radius,
    // -height): the point goes to the nearest point of it, which for a flat cone as for a
    // steep one moves it no further than its error.
    double distance, ux, uz;
    across_axis(p, distance, ux, uz);
    const double along =
        std::clamp((distance * cone.radius - p.y * cone.height) / cone.slant, 0.0, cone.slant);
    const double out = along * cone.radius / cone.slant;
    snapped = Vec3(out * ux, -along * cone.height / cone.slant, out * uz);
    // At the apex itself, where the side has no normal, it points up the axis.
    normal = distance > 0.0 ? Vec3(cone.height * ux, cone.radius, cone.height * uz)
                            : Vec3(0.0, 1.0, 0.0);
  } else {
    snapped = cap_point(p, -cone.height, cone.radius);
    normal = Vec3(0.0, -1.0, 0.0);
  }
  finish_axial_hit(cone.apex + snapped, normal, cone.object_to_world, cone.normal_matrix, hit);
}

void finish_plane_hit(const Ray& ray, const PlaneSet& set, unsigned index, double exact_t,
                      SurfaceHit& hit) {
  const PreparedPlane& plane = set.planes[index];
  hit.object = set.objects[index];
  hit.t = exact_t;
  double p[3];
  plane_hit(ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y,
            ray.direction.z, hit.t, plane.point.x, plane.point.y, plane.point.z, plane.normal.x,
            plane.normal.y, plane.normal.z, p);
  hit.position = Vec3(p[0], p[1], p[2]);
  hit.normal = plane.normal;
  hit.shading_normal = plane.normal;
}

// No callback computed a triangle's hit: Embree's t, u and v stand in only where the
// recomputation finds the ray parallel to the triangle. `o` and `d`: the ray in the mesh's
// space. The hit is left in that space.
void finish_triangle_hit(const Vec3& o, const Vec3& d, const TriangleMesh& mesh, unsigned index,
                         float t, float u, float v, SurfaceHit& hit) {
  glm::vec3 corners[3];
  mesh_corners(mesh, index, corners);
  const Vec3 v0(corners[0]);
  const Vec3 v1(corners[1]);
  const Vec3 v2(corners[2]);
  const TriangleHit th = intersect_triangle(v0, v1, v2, o, d).value_or(TriangleHit{t, u, v});
  hit.t = th.t;
  // Barycentric reconstruction keeps the point on the triangle's own plane.
  hit.position = (1.0 - th.u - th.v) * v0 + th.u * v1 + th.v * v2;
  hit.normal = mesh.compact() ? triangle_normal(corners[0], corners[1], corners[2])
                              : mesh.triangles[index].normal;
  hit.shading_normal = hit.normal;
  const bool smooth = mesh.compact() ? !mesh.vertex_normals.empty() : !mesh.normals.empty();
  if (smooth) {
    glm::vec3 normals[3];
    if (mesh.compact()) {
      for (int k = 0; k < 3; ++k) normals[k] = mesh.vertex_normals[mesh.indices[3 * index + k]];
    } else {
      for (int k = 0; k < 3; ++k) normals[k] = mesh.normals[index].corners[k];
    }
    const Vec3 n =
        (1.0 - th.u - th.v) * Vec3(normals[0]) + th.u * Vec3(normals[1]) + th.v * Vec3(normals[2]);
    if (glm::dot(n, n) > 0.0) hit.shading_normal = glm::normalize(n);
  }
}

// A hit on a placed mesh: rebuilt in object space, on the triangle Embree found there, then
// placed in the world. Interpolating the shading normal before the transform or after it
// points it alike: the normal matrix is linear.
void finish_placed_mesh_hit(const Ray& ray, const PlacedMesh& placed, unsigned index, float t,
                            float u, float v, SurfaceHit& hit) {
  const Vec3 o(placed.world_to_object * glm::dvec4(Vec3(ray.origin), 1.0));
  const Vec3 d = glm::dmat3(placed.world_to_object) * Vec3(ray.direction);
  finish_triangle_hit(o, d, placed.bvh->mesh(), index, t, u, v, hit);
  hit.position = Vec3(placed.object_to_world * glm::dvec4(hit.position, 1.0));
  const bool flat = hit.shading_normal == hit.normal;
  hit.normal = glm::normalize(placed.normal_matrix * hit.normal);
  hit.shading_normal =
      flat ? hit.normal : glm::normalize(placed.normal_matrix * hit.shading_normal);
}

}  // namespace

int SceneGeometry::nearest_opaque_plane(const Ray& ray, float t_max, unsigned mask,
                                        double& t) const {
  if ((mask & kOpaquePlaneMask) == 0 || plane_sets_[0].planes.empty()) return -1;
  const int plane = nearest_plane(plane_sets_[0], ray.origin, ray.direction, t);
  // As the packets have it: t < t_max, compared in double.
  return plane >= 0 && t < t_max ? plane : -1;
}

std::optional<SurfaceHit> SceneGeometry::intersect(const Ray& ray, float t_max,
                                                   unsigned mask) const {
  // The packets' way, lane for lane: the nearest opaque plane first, then Embree for
  // anything nearer.
  double plane_t = kInfinity;
  const int plane = nearest_opaque_plane(ray, t_max, mask, plane_t);
  if (plane >= 0) t_max = static_cast<float>(plane_t);
  HitContext context;
  rtcInitIntersectContext(&context.embree);
  RTCRayHit rayhit{};
  rayhit.ray.org_x = ray.origin.x;
  rayhit.ray.org_y = ray.origin.y;
  rayhit.ray.org_z = ray.origin.z;
  rayhit.ray.dir_x = ray.direction.x;
  rayhit.ray.dir_y = ray.direction.y;
  rayhit.ray.dir_z = ray.direction.z;
  rayhit.ray.tnear = 0.0f;
  rayhit.ray.tfar = t_max;
  rayhit.ray.mask = mask & ~kOpaquePlaneMask;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_.get(), &context.embree, &rayhit);
  std::optional<SurfaceHit> hit;
  // A hit inside a placed mesh names the instance first (see GeometryRecord).
  const unsigned geometry =
      rayhit.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rayhit.hit.instID[0] : rayhit.hit.geomID;
  if (geometry != RTC_INVALID_GEOMETRY_ID)
    finish_hit(ray, geometry, rayhit.hit.primID, rayhit.ray.tfar, rayhit.hit.u, rayhit.hit.v,
               context.t[0], hit.emplace());
  else if (plane >= 0)
    finish_hit(ray, opaque_planes_geometry_, static_cast<unsigned>(plane), rayhit.ray.tfar, 0.0f,
               0.0f, plane_t, hit.emplace());
  return hit;
}

bool SceneGeometry::occluded(const Ray& ray, float t_max, unsigned mask) const {
  double plane_t;
  if (nearest_opaque_plane(ray, t_max, mask, plane_t) >= 0) return true;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r{};
  r.org_x = ray.origin.x;
  r.org_y = ray.origin.y;
  r.org_z = ray.origin.z;
  r.dir_x = ray.direction.x;
  r.dir_y = ray.direction.y;
  r.dir_z = ray.direction.z;
  r.tnear = 0.0f;
  r.tfar = t_max;
  r.mask = mask & ~kOpaquePlaneMask;
  rtcOccluded1(scene_.get(), &context, &r);
  return r.tfar < 0.0f;
}

void SceneGeometry::finish_hit(const Ray& ray, unsigned geometry, unsigned primitive, float t,
                               float u, float v, double exact_t, SurfaceHit& hit) const {
  const GeometryRecord& record = records_[geometry];
  hit.object = record.object;
  hit.primitive = record.kind == Kind::plane ? 0 : primitive;
  switch (record.kind) {
    case Kind::sphere:
      finish_sphere_hit(ray, *spheres_[record.index], exact_t, hit);
      break;
    case Kind::box:
      finish_box_hit(ray, *boxes_[record.index], primitive, exact_t, hit);
      break;
    case Kind::plane:
      finish_plane_hit(ray, plane_sets_[record.index], primitive, exact_t, hit);
      break;
    case Kind::triangles:
      finish_triangle_hit(Vec3(ray.origin), Vec3(ray.direction), meshes_[record.index], primitive,
                          t, u, v, hit);
      break;
    case Kind::placed_mesh:
      finish_placed_mesh_hit(ray, placed_meshes_[record.index], primitive, t, u, v, hit);
      break;
    case Kind::cylinder:
      finish_cylinder_hit(ray, *cylinders_[record.index], primitive, exact_t, hit);
      break;
    case Kind::cone:
      finish_cone_hit(ray, *cones_[record.index], primitive, exact_t, hit);
      break;
  }
}

}  // namespace tessera
