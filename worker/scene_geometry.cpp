// SceneGeometry's queries: single rays and packets of sixteen, for the nearest hit and for
// occlusion, and the hits rebuilt in double. (finish_hit() stays in this file: GCC inlines
// it into the packet loops here, and from another file, even with link-time optimisation,
// the showcase took 1.1% more instructions.)
#include "worker/scene_geometry.hpp"

#include <algorithm>
#include <cmath>

#include "worker/user_geometry.hpp"

namespace tessera {
namespace {

struct TriangleHit {
  double t, u, v;
};

// Möller–Trumbore in double: recomputes the hit Embree found, from the ray's floats.
std::optional<TriangleHit> intersect_triangle(const Vec3& v0, const Vec3& v1, const Vec3& v2,
                                              const Ray& ray) {
  const Vec3 o(ray.origin);
  const Vec3 d(ray.direction);
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

// A hit on a sphere that is a sphere in world space too, from the ray and the exact
// distance t: the unit normal at o + t·d, and the point snapped onto the surface along it,
// which removes the error that o + t·d accumulates. On scalars, so that the packets' loop
// over lanes vectorises, in glm's order of operations (normalize(v) is v · (1 / sqrt(v·v)),
// sums go (x + y) + z), so that a single ray's hit has the same bits as a lane's.
[[gnu::always_inline]] inline void world_sphere_hit(double ox, double oy, double oz, double dx,
                                                    double dy, double dz, double t, double cx,
                                                    double cy, double cz, double radius,
                                                    double (&normal)[3], double (&point)[3]) {
  const double vx = ox + t * dx - cx;
  const double vy = oy + t * dy - cy;
  const double vz = oz + t * dz - cz;
  const double inverse_length = 1.0 / std::sqrt(vx * vx + vy * vy + vz * vz);
  normal[0] = vx * inverse_length;
  normal[1] = vy * inverse_length;
  normal[2] = vz * inverse_length;
  point[0] = cx + radius * normal[0];
  point[1] = cy + radius * normal[1];
  point[2] = cz + radius * normal[2];
}

// A hit on a plane through q with unit normal n: o + t·d projected onto the plane, which
// removes the error that o + t·d accumulates. Scalars and glm's order, as above.
[[gnu::always_inline]] inline void plane_hit(double ox, double oy, double oz, double dx, double dy,
                                             double dz, double t, double qx, double qy, double qz,
                                             double nx, double ny, double nz, double (&point)[3]) {
  const double px = ox + t * dx;
  const double py = oy + t * dy;
  const double pz = oz + t * dz;
  const double height = (px - qx) * nx + (py - qy) * ny + (pz - qz) * nz;
  point[0] = px - height * nx;
  point[1] = py - height * ny;
  point[2] = pz - height * nz;
}

}  // namespace

void SceneGeometry::may_meet_transmissive(const RayPacket& packet,
                                          const float (&t_max)[kPacketSize],
                                          const std::uint32_t (&left)[kPacketSize],
                                          bool (&may)[kPacketSize]) const {
  // The single ray's test, lane by lane: GCC runs a box's test on eight or sixteen lanes at
  // once (AVX2, AVX-512).
  const auto& o = packet.origin;
  const auto& d = packet.direction;
  // Flags as wide as the floats: with bools beside them, GCC finds no vector shape for both.
  std::int32_t any[kPacketSize] = {};
  for (const TransmissiveBounds& box : transmissive_bounds_)
    for (int i = 0; i < kPacketSize; ++i)
      any[i] |= tested(box, left[i]) & geometry_detail::may_meet_box(o[0][i], o[1][i], o[2][i],
                                                                     d[0][i], d[1][i], d[2][i],
                                                                     box.lo, box.hi, t_max[i]);
  for (int i = 0; i < kPacketSize; ++i)
    may[i] = (packet.active[i] & static_cast<std::uint8_t>(any[i])) != 0;
}

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
  if (rayhit.hit.geomID != RTC_INVALID_GEOMETRY_ID)
    finish_hit(ray, rayhit.hit.geomID, rayhit.hit.primID, rayhit.ray.tfar, rayhit.hit.u,
               rayhit.hit.v, context.t[0], hit.emplace());
  else if (plane >= 0)
    finish_hit(ray, opaque_planes_geometry_, static_cast<unsigned>(plane), rayhit.ray.tfar, 0.0f,
               0.0f, plane_t, hit.emplace());
  return hit;
}

namespace {

// The fields every packet fills the same way, each in a loop of its own: sixteen lanes of a
// constant are four vector stores, where a loop over lanes writing every field of a lane
// is a store per field and lane.
template <typename Rays>
void load_rays(const RayPacket& packet, int (&valid)[kPacketSize], Rays& rays) {
  for (int i = 0; i < kPacketSize; ++i) valid[i] = packet.active[i] ? -1 : 0;
  for (int i = 0; i < kPacketSize; ++i) rays.org_x[i] = packet.origin[0][i];
  for (int i = 0; i < kPacketSize; ++i) rays.org_y[i] = packet.origin[1][i];
  for (int i = 0; i < kPacketSize; ++i) rays.org_z[i] = packet.origin[2][i];
  for (int i = 0; i < kPacketSize; ++i) rays.dir_x[i] = packet.direction[0][i];
  for (int i = 0; i < kPacketSize; ++i) rays.dir_y[i] = packet.direction[1][i];
  for (int i = 0; i < kPacketSize; ++i) rays.dir_z[i] = packet.direction[2][i];
  for (int i = 0; i < kPacketSize; ++i) rays.tnear[i] = 0.0f;
  for (int i = 0; i < kPacketSize; ++i) rays.time[i] = 0.0f;
  for (int i = 0; i < kPacketSize; ++i) rays.id[i] = static_cast<unsigned>(i);
  for (int i = 0; i < kPacketSize; ++i) rays.flags[i] = 0;
}

}  // namespace

void load_packet(const RayPacket& packet, int (&valid)[kPacketSize], RTCRayHit16& rayhit,
                 unsigned mask) {
  load_rays(packet, valid, rayhit.ray);
  for (int i = 0; i < kPacketSize; ++i) rayhit.ray.tfar[i] = kInfinity;
  for (int i = 0; i < kPacketSize; ++i) rayhit.ray.mask[i] = mask;
  for (int i = 0; i < kPacketSize; ++i) rayhit.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
  for (int i = 0; i < kPacketSize; ++i) rayhit.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

void SceneGeometry::intersect(const RayPacket& packet, SurfaceHit (&hits)[kPacketSize],
                              bool (&found)[kPacketSize]) const {
  intersect(packet, nullptr, kAnyMask, hits, found);
}

void SceneGeometry::intersect(const RayPacket& packet, const float (&t_max)[kPacketSize],
                              unsigned mask, SurfaceHit (&hits)[kPacketSize],
                              bool (&found)[kPacketSize]) const {
  intersect(packet, &t_max, mask, hits, found);
}

void SceneGeometry::intersect(const RayPacket& packet, const float (*t_max)[kPacketSize],
                              unsigned mask, SurfaceHit (&hits)[kPacketSize],
                              bool (&found)[kPacketSize]) const {
  HitContext context;
  rtcInitIntersectContext(&context.embree);
  context.embree.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(64) int valid[kPacketSize];
  alignas(64) RTCRayHit16 rayhit;
  // Opaque planes are tested here, on all lanes at once (see OpaquePlanes); Embree then
  // looks only for something nearer than each lane's plane.
  const bool opaque_planes =
      (mask & kOpaquePlaneMask) != 0 && opaque_planes_geometry_ != RTC_INVALID_GEOMETRY_ID;
  load_packet(packet, valid, rayhit, opaque_planes ? mask & ~kOpaquePlaneMask : mask);
  if (t_max != nullptr)
    for (int i = 0; i < kPacketSize; ++i) rayhit.ray.tfar[i] = (*t_max)[i];
  double plane_t[kPacketSize] = {};
  int plane[kPacketSize];
  for (int i = 0; i < kPacketSize; ++i) plane[i] = -1;
  if (opaque_planes) {
    nearest_planes(plane_sets_[0], rayhit, valid, plane_t, plane);
    for (int i = 0; i < kPacketSize; ++i) {
      // As the plane callback has it: t < t_max, compared in double. Without branches, so
      // that the lanes go through together.
      const bool nearer = (plane[i] >= 0) & (plane_t[i] < rayhit.ray.tfar[i]);
      rayhit.ray.tfar[i] = nearer ? static_cast<float>(plane_t[i]) : rayhit.ray.tfar[i];
      plane[i] = nearer ? plane[i] : -1;
    }
  }
  // The callbacks set the lanes they hit; the others are read too, below.
  for (double& t : context.t) t = 0.0;
  rtcIntersect16(valid, scene_.get(), &context.embree, &rayhit);
  // Hits on world spheres and on planes, nearly all hits in most scenes, are rebuilt for all
  // sixteen lanes at once, in loops the compiler vectorises: lane by lane, each sphere's
  // square root and division made the next lane wait (a fifth of the ray-casting
  // benchmark's time went there). First each lane's shape is gathered; other hits go
  // through finish_hit() afterwards.
  enum class Rebuilt : std::uint8_t { none, sphere, plane, other };
  Rebuilt rebuilt[kPacketSize];
  unsigned geometry[kPacketSize];
  unsigned primitive[kPacketSize];
  double t[kPacketSize];
  double anchor[3][kPacketSize];  // a sphere's centre, a point on a plane
  double radius[kPacketSize];
  double normal[3][kPacketSize];  // a plane's
  // Each lane's hit, Embree's or else the opaque plane's, and the arrays the lanes without
  // a sphere or a plane keep at zero: without branches, so that every lane is done at once.
  for (int i = 0; i < kPacketSize; ++i) {
    const bool by_plane = (rayhit.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) & (plane[i] >= 0);
    geometry[i] = by_plane ? opaque_planes_geometry_ : rayhit.hit.geomID[i];
    primitive[i] = by_plane ? static_cast<unsigned>(plane[i]) : rayhit.hit.primID[i];
    const bool hit = packet.active[i] & (geometry[i] != RTC_INVALID_GEOMETRY_ID);
    t[i] = !hit ? 0.0 : by_plane ? plane_t[i] : context.t[i];
    rebuilt[i] = hit ? Rebuilt::other : Rebuilt::none;
  }
  for (int i = 0; i < kPacketSize; ++i) radius[i] = 0.0;
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 0; i < kPacketSize; ++i) anchor[axis][i] = normal[axis][i] = 0.0;
  for (int i = 0; i < kPacketSize; ++i) {
    if (rebuilt[i] == Rebuilt::none) continue;
    const GeometryRecord& record = records_[geometry[i]];
    if (record.kind == Kind::sphere && spheres_[record.index]->world_sphere) {
      const PreparedSphere& sphere = *spheres_[record.index];
      rebuilt[i] = Rebuilt::sphere;
      hits[i].object = record.object;
      for (int axis = 0; axis < 3; ++axis) anchor[axis][i] = sphere.world_center[axis];
      radius[i] = sphere.world_radius;
    } else if (record.kind == Kind::plane) {
      const PlaneSet& set = plane_sets_[record.index];
      const PreparedPlane& prepared = set.planes[primitive[i]];
      rebuilt[i] = Rebuilt::plane;
      hits[i].object = set.objects[primitive[i]];
      for (int axis = 0; axis < 3; ++axis) {
        anchor[axis][i] = prepared.point[axis];
        normal[axis][i] = prepared.normal[axis];
      }
    } else {
      if (record.kind != Kind::triangles) continue;
      t[i] = 0.0;  // no callback's: finish_hit() recomputes a triangle's
      // A mesh's triangles are read back from memory Embree's traversal did not touch, and
      // a large mesh's are far out of cache: asking for all sixteen before finish_hit()
      // reads the first lets their misses overlap instead of coming one after another.
      const TriangleMesh& mesh = meshes_[record.index];
      __builtin_prefetch(&mesh.triangles[primitive[i]]);
      if (mesh.normals.empty()) continue;
      // Both ends: 36 bytes often straddle two cache lines.
      const auto* normals = reinterpret_cast<const char*>(&mesh.normals[primitive[i]]);
      __builtin_prefetch(normals);
      __builtin_prefetch(normals + sizeof(MeshTriangleNormals) - 1);
    }
  }
  // Each kind's rebuild runs on all sixteen lanes, the lanes of other kinds on harmless
  // zeros, and only where some lane needs it: packets of secondary rays often hold a few
  // active lanes, all of one kind.
  bool any_sphere = false;
  bool any_plane = false;
  for (int i = 0; i < kPacketSize; ++i) {
    any_sphere = any_sphere | (rebuilt[i] == Rebuilt::sphere);
    any_plane = any_plane | (rebuilt[i] == Rebuilt::plane);
  }
  const auto& o = packet.origin;
  const auto& d = packet.direction;
  double sphere_normal[3][kPacketSize];
  double sphere_point[3][kPacketSize];
  double plane_point[3][kPacketSize];
  if (any_sphere)
    for (int i = 0; i < kPacketSize; ++i) {
      double n[3];
      double p[3];
      world_sphere_hit(o[0][i], o[1][i], o[2][i], d[0][i], d[1][i], d[2][i], t[i], anchor[0][i],
                       anchor[1][i], anchor[2][i], radius[i], n, p);
      for (int axis = 0; axis < 3; ++axis) {
        sphere_normal[axis][i] = n[axis];
        sphere_point[axis][i] = p[axis];
      }
    }
  if (any_plane)
    for (int i = 0; i < kPacketSize; ++i) {
      double p[3];
      plane_hit(o[0][i], o[1][i], o[2][i], d[0][i], d[1][i], d[2][i], t[i], anchor[0][i],
                anchor[1][i], anchor[2][i], normal[0][i], normal[1][i], normal[2][i], p);
      for (int axis = 0; axis < 3; ++axis) plane_point[axis][i] = p[axis];
    }
  for (int i = 0; i < kPacketSize; ++i) {
    found[i] = rebuilt[i] != Rebuilt::none;
    if (rebuilt[i] == Rebuilt::other)
      finish_hit(packet.ray(i), geometry[i], primitive[i], rayhit.ray.tfar[i], rayhit.hit.u[i],
                 rayhit.hit.v[i], t[i], hits[i]);
    if ((rebuilt[i] != Rebuilt::sphere) & (rebuilt[i] != Rebuilt::plane)) continue;
    const bool sphere = rebuilt[i] == Rebuilt::sphere;
    // Each member stored from registers: copying the normal just stored into the shading
    // normal would load it back before its pieces reached the cache, and stall.
    // The lane's own array is chosen before it is read: the other may not have been written.
    const auto pick = [&](const double(&a)[3][kPacketSize], const double(&b)[3][kPacketSize]) {
      const auto& chosen = sphere ? a : b;
      return Vec3(chosen[0][i], chosen[1][i], chosen[2][i]);
    };
    const Vec3 n = pick(sphere_normal, normal);
    SurfaceHit& hit = hits[i];
    hit.t = t[i];
    hit.position = pick(sphere_point, plane_point);
    hit.normal = n;
    hit.shading_normal = n;
  }
}

void SceneGeometry::occluded(const RayPacket& packet, const float (&t_max)[kPacketSize],
                             unsigned mask, bool (&blocked)[kPacketSize]) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  alignas(64) int valid[kPacketSize];
  alignas(64) RTCRay16 rays;
  load_rays(packet, valid, rays);
  for (int i = 0; i < kPacketSize; ++i) rays.tfar[i] = packet.active[i] ? t_max[i] : 0.0f;
  // Opaque planes are tested here, on all lanes at once (see OpaquePlanes), and the lanes
  // they block need no traversal at all.
  const PlaneSet& opaque_planes = plane_sets_[0];
  const bool planes_here = (mask & kOpaquePlaneMask) != 0 && !opaque_planes.planes.empty();
  const unsigned embree_mask = planes_here ? mask & ~kOpaquePlaneMask : mask;
  for (int i = 0; i < kPacketSize; ++i) rays.mask[i] = embree_mask;
  bool by_plane[kPacketSize] = {};
  if (planes_here) {
    planes_occlude(opaque_planes, rays, valid, by_plane);
    bool any_left = false;
    for (int i = 0; i < kPacketSize; ++i) {
      if (by_plane[i]) valid[i] = 0;
      any_left = any_left | (valid[i] != 0);
    }
    if (!any_left) {
      for (int i = 0; i < kPacketSize; ++i) blocked[i] = by_plane[i];
      return;
    }
  }
  rtcOccluded16(valid, scene_.get(), &context, &rays);
  // Bitwise, not short-circuit, here and in the other loops over lanes' flags: the same
  // answers without a branch per lane (half the instructions of this loop).
  for (int i = 0; i < kPacketSize; ++i)
    blocked[i] = by_plane[i] | (packet.active[i] & (rays.tfar[i] < 0.0f));
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
  switch (record.kind) {
    case Kind::sphere: {
      const PreparedSphere& sphere = *spheres_[record.index];
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
        break;
      }
      const Vec3 o = Vec3(sphere.world_to_object * glm::dvec4(Vec3(ray.origin), 1.0));
      const Vec3 d = glm::dmat3(sphere.world_to_object) * Vec3(ray.direction);
      const Vec3 n = glm::normalize(o + hit.t * d - sphere.center);
      // Snapping the point onto the surface removes the error that o + t·d accumulates.
      hit.position =
          Vec3(sphere.object_to_world * glm::dvec4(sphere.center + sphere.radius * n, 1.0));
      hit.normal = glm::normalize(glm::transpose(glm::dmat3(sphere.world_to_object)) * n);
      hit.shading_normal = hit.normal;
      break;
    }
    case Kind::box: {
      const PreparedBox& box = *boxes_[record.index];
      hit.t = exact_t;
      Vec3 o(ray.origin);
      Vec3 d(ray.direction);
      if (!box.world_box) {
        o = Vec3(box.world_to_object * glm::dvec4(o, 1.0));
        d = glm::dmat3(box.world_to_object) * d;
      }
      // Snapping the point onto its face removes the error that o + t·d accumulates.
      Vec3 p = glm::clamp(o + hit.t * d, box.lo, box.hi);
      const unsigned axis = primitive / 2;
      p[axis] = primitive % 2 == 1 ? box.hi[axis] : box.lo[axis];
      hit.position = box.world_box ? p : Vec3(box.object_to_world * glm::dvec4(p, 1.0));
      hit.normal = box.face_normals[primitive];
      hit.shading_normal = hit.normal;
      break;
    }
    case Kind::plane: {
      const PlaneSet& set = plane_sets_[record.index];
      const PreparedPlane& plane = set.planes[primitive];
      hit.object = set.objects[primitive];
      hit.t = exact_t;
      double p[3];
      plane_hit(ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y,
                ray.direction.z, hit.t, plane.point.x, plane.point.y, plane.point.z, plane.normal.x,
                plane.normal.y, plane.normal.z, p);
      hit.position = Vec3(p[0], p[1], p[2]);
      hit.normal = plane.normal;
      hit.shading_normal = plane.normal;
      break;
    }
    case Kind::triangles: {
      const TriangleMesh& mesh = meshes_[record.index];
      const MeshTriangle& triangle = mesh.triangles[primitive];
      const Vec3 v0(triangle.corners[0]);
      const Vec3 v1(triangle.corners[1]);
      const Vec3 v2(triangle.corners[2]);
      const TriangleHit th = intersect_triangle(v0, v1, v2, ray).value_or(TriangleHit{t, u, v});
      hit.t = th.t;
      // Barycentric reconstruction keeps the point on the triangle's own plane.
      hit.position = (1.0 - th.u - th.v) * v0 + th.u * v1 + th.v * v2;
      hit.normal = triangle.normal;
      hit.shading_normal = hit.normal;
      if (!mesh.normals.empty()) {
        const MeshTriangleNormals& normals = mesh.normals[primitive];
        const Vec3 n = (1.0 - th.u - th.v) * Vec3(normals.corners[0]) +
                       th.u * Vec3(normals.corners[1]) + th.v * Vec3(normals.corners[2]);
        if (glm::dot(n, n) > 0.0) hit.shading_normal = glm::normalize(n);
      }
      break;
    }
  }
}

}  // namespace tessera
