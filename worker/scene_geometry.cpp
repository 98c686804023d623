#include "worker/scene_geometry.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "worker/triangulate.hpp"
#include "worker/user_geometry.hpp"

namespace tessera {
namespace {

constexpr Ray kIdleRay{glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f)};

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

}  // namespace

SceneGeometry::SceneGeometry(const Scene& scene, const EmbreeDevice& device,
                             OpaquePlanes opaque_planes)
    : device_(device), scene_(device) {
  for (std::uint32_t i = 0; i < scene.objects.size(); ++i) {
    const Object& object = scene.objects[i];
    const Color& transmission = scene.materials[object.material].transmission;
    const bool transmissive = transmission.r != 0.0 || transmission.g != 0.0 || transmission.b != 0.0;
    const unsigned mask = transmissive ? kTransmissiveMask : kOpaqueSolidMask;
    std::visit(
        [&](const auto& shape) {
          using T = std::decay_t<decltype(shape)>;
          if constexpr (std::is_same_v<T, Sphere>)
            add_sphere(shape, object.transform, i, mask);
          else if constexpr (std::is_same_v<T, Box>)
            add_box(shape, object.transform, i, mask);
          else if constexpr (std::is_same_v<T, Plane>)
            add_plane(shape, object.transform, i, transmissive);
          else
            add_triangles(triangulate(shape, object.transform), i, mask);
        },
        object.shape);
    if (transmissive) {
      // A plane has no record yet (the plane sets are added last), and no bounds anyway.
      const bool plane = std::holds_alternative<Plane>(object.shape);
      const auto [lo, hi] = plane ? std::pair(glm::vec3(-kInfinity), glm::vec3(kInfinity))
                                  : geometry_bounds(records_.back());
      transmissive_lo_ = glm::min(transmissive_lo_, lo);
      transmissive_hi_ = glm::max(transmissive_hi_, hi);
    }
  }
  if (!plane_sets_[1].planes.empty()) add_user_geometry(Kind::plane, 1, 0, kTransmissiveMask);
  if (!plane_sets_[0].planes.empty()) {
    opaque_planes_geometry_ = static_cast<unsigned>(records_.size());
    if (opaque_planes == OpaquePlanes::also_in_embree)
      add_user_geometry(Kind::plane, 0, 0, kOpaquePlaneMask);
    else
      records_.push_back({Kind::plane, 0, 0});
  }
  // Robust traversal closes the hairline cracks between neighbouring mesh triangles.
  rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene_.get());
  device_.check("building the scene's BVH");
}

void SceneGeometry::add_user_geometry(Kind kind, std::uint32_t index, std::uint32_t object,
                                      unsigned mask) {
  RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geometry, 1);
  rtcSetGeometryMask(geometry, mask);
  if (kind == Kind::sphere) {
    rtcSetGeometryUserData(geometry, spheres_[index].get());
    set_sphere_callbacks(geometry);
  } else if (kind == Kind::box) {
    rtcSetGeometryUserData(geometry, boxes_[index].get());
    set_box_callbacks(geometry);
  } else {
    rtcSetGeometryUserData(geometry, &plane_sets_[index]);
    set_plane_callbacks(geometry);
  }
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene_.get(), geometry);
  rtcReleaseGeometry(geometry);
  device_.check("adding a user geometry");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");
  records_.push_back({kind, index, object});
}

void SceneGeometry::add_sphere(const Sphere& sphere, const Mat4& transform, std::uint32_t object,
                               unsigned mask) {
  auto prepared = std::make_unique<PreparedSphere>();
  prepared->center = sphere.center;
  prepared->radius = sphere.radius;
  prepared->object_to_world = transform;
  prepared->world_to_object = glm::inverse(transform);
  // A similarity has orthogonal columns of one common length: MᵀM = s²·I.
  const glm::dmat3 linear(transform);
  const glm::dmat3 gram = glm::transpose(linear) * linear;
  const double scale2 = (gram[0][0] + gram[1][1] + gram[2][2]) / 3.0;
  bool similarity = scale2 > 0.0;
  for (int i = 0; i < 3 && similarity; ++i)
    for (int j = 0; j < 3; ++j)
      similarity = similarity && std::fabs(gram[i][j] - (i == j ? scale2 : 0.0)) <= 1e-12 * scale2;
  if (similarity) {
    prepared->world_sphere = true;
    prepared->world_center = Vec3(transform * glm::dvec4(sphere.center, 1.0));
    prepared->world_radius = sphere.radius * std::sqrt(scale2);
  }
  spheres_.push_back(std::move(prepared));
  add_user_geometry(Kind::sphere, static_cast<std::uint32_t>(spheres_.size() - 1), object, mask);
}

void SceneGeometry::add_box(const Box& box, const Mat4& transform, std::uint32_t object,
                            unsigned mask) {
  auto prepared = std::make_unique<PreparedBox>();
  prepared->object_to_world = transform;
  prepared->world_to_object = glm::inverse(transform);
  const glm::dmat3 linear(transform);
  bool along_axes = true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) along_axes = along_axes && (i == j || linear[i][j] == 0.0);
  if (along_axes) {
    // A scale along the axes, negative ones included, keeps the box axis-aligned.
    const Vec3 a(transform * glm::dvec4(box.min, 1.0));
    const Vec3 b(transform * glm::dvec4(box.max, 1.0));
    prepared->world_box = true;
    prepared->lo = glm::min(a, b);
    prepared->hi = glm::max(a, b);
    for (int face = 0; face < 6; ++face) {
      Vec3 n(0.0);
      n[face / 2] = face % 2 == 1 ? 1.0 : -1.0;
      prepared->face_normals[face] = n;
    }
  } else {
    prepared->lo = box.min;
    prepared->hi = box.max;
    // Normals go through the inverse transpose, which keeps an outward normal outward even
    // under a mirroring transform.
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    for (int face = 0; face < 6; ++face) {
      Vec3 n(0.0);
      n[face / 2] = face % 2 == 1 ? 1.0 : -1.0;
      prepared->face_normals[face] = glm::normalize(normal_matrix * n);
    }
  }
  boxes_.push_back(std::move(prepared));
  add_user_geometry(Kind::box, static_cast<std::uint32_t>(boxes_.size() - 1), object, mask);
}

void SceneGeometry::add_plane(const Plane& plane, const Mat4& transform, std::uint32_t object,
                              bool transmissive) {
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
  const Vec3 point(transform * glm::dvec4(plane.point, 1.0));
  const Vec3 normal = glm::normalize(normal_matrix * plane.normal);
  PlaneSet& set = plane_sets_[transmissive ? 1 : 0];
  set.planes.push_back(PreparedPlane{point, normal, glm::dot(normal, point)});
  set.objects.push_back(object);
}

void SceneGeometry::add_triangles(PreparedTriangles triangles, std::uint32_t object,
                                  unsigned mask) {
  RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryMask(geometry, mask);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               triangles.positions.size()));
  auto* indices = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), triangles.triangles.size()));
  device_.check("allocating a triangle mesh");
  for (std::size_t i = 0; i < triangles.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) vertices[3 * i + k] = static_cast<float>(triangles.positions[i][k]);
  static_assert(sizeof(triangles.triangles[0]) == 3 * sizeof(unsigned));
  std::memcpy(indices, triangles.triangles.data(),
              triangles.triangles.size() * 3 * sizeof(unsigned));
  rtcCommitGeometry(geometry);
  const unsigned id = rtcAttachGeometry(scene_.get(), geometry);
  rtcReleaseGeometry(geometry);
  device_.check("adding a triangle mesh");
  if (id != records_.size()) throw std::logic_error("Embree geometry ids are not sequential");
  TriangleMesh mesh;
  mesh.triangles.reserve(triangles.triangles.size());
  if (!triangles.normals.empty()) mesh.normals.reserve(triangles.triangles.size());
  for (const auto& tri : triangles.triangles) {
    MeshTriangle& corners = mesh.triangles.emplace_back();
    for (int k = 0; k < 3; ++k) corners.corners[k] = glm::vec3(triangles.positions[tri[k]]);
    if (triangles.normals.empty()) continue;
    MeshTriangleNormals& normals = mesh.normals.emplace_back();
    for (int k = 0; k < 3; ++k) normals.corners[k] = glm::vec3(triangles.normals[tri[k]]);
  }
  // From the stored floats, in a pass of its own: in the loop above, GCC 12's vectoriser
  // was seen to use the doubles the floats were rounded from (a different normal, and other
  // pixels, than finish_hit() computed from the floats).
  for (MeshTriangle& triangle : mesh.triangles) {
    const Vec3 v0(triangle.corners[0]);
    triangle.normal =
        glm::normalize(glm::cross(Vec3(triangle.corners[1]) - v0, Vec3(triangle.corners[2]) - v0));
  }
  meshes_.push_back(std::move(mesh));
  records_.push_back({Kind::triangles, static_cast<std::uint32_t>(meshes_.size() - 1), object});
}

std::pair<glm::vec3, glm::vec3> SceneGeometry::geometry_bounds(
    const GeometryRecord& record) const {
  if (record.kind == Kind::sphere || record.kind == Kind::box) {
    RTCBounds bounds{};
    RTCBoundsFunctionArguments args{};
    args.bounds_o = &bounds;
    if (record.kind == Kind::sphere) {
      args.geometryUserPtr = spheres_[record.index].get();
      sphere_bounds(&args);
    } else {
      args.geometryUserPtr = boxes_[record.index].get();
      box_bounds(&args);
    }
    return {{bounds.lower_x, bounds.lower_y, bounds.lower_z},
            {bounds.upper_x, bounds.upper_y, bounds.upper_z}};
  }
  // A mesh: its corners are floats already, so their extremes bound it exactly.
  glm::vec3 lo(kInfinity);
  glm::vec3 hi(-kInfinity);
  for (const MeshTriangle& triangle : meshes_[record.index].triangles)
    for (const glm::vec3& p : triangle.corners) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  return {lo, hi};
}

bool SceneGeometry::may_meet_transmissive(const Ray& ray, float t_max) const {
  // Without branches, so that a packet's lanes go through it without mispredictions. Where a
  // direction component is zero the quotients are infinite, which leaves the interval as it
  // is when the origin lies inside the slab and empties it when it lies outside; NaN (the
  // origin on a face) fails every comparison below and leaves it as it is too. `outside`
  // also catches the one case the infinities miss, an infinite t_max.
  float t_near = 0.0f;
  float t_far = t_max;
  bool outside = false;
  for (int axis = 0; axis < 3; ++axis) {
    const float o = ray.origin[axis];
    const float d = ray.direction[axis];
    const float lo = transmissive_lo_[axis];
    const float hi = transmissive_hi_[axis];
    outside |= (d == 0.0f) & ((o < lo) | (o > hi));
    float t0 = (lo - o) / d;
    float t1 = (hi - o) / d;
    const bool swap = t0 > t1;
    const float entry = swap ? t1 : t0;
    const float exit = swap ? t0 : t1;
    // Widened by a few ulps so that rounding can only let a ray through, never cut one off.
    t_near = std::max(t_near, entry * (1.0f - 1e-5f));
    t_far = std::min(t_far, exit * (1.0f + 1e-5f));
  }
  return !outside && !(t_near > t_far);
}

void SceneGeometry::may_meet_transmissive(const RayPacket& packet,
                                          const float (&t_max)[kPacketSize],
                                          bool (&may)[kPacketSize]) const {
  for (int i = 0; i < kPacketSize; ++i)
    may[i] = packet.active[i] && may_meet_transmissive(packet.rays[i], t_max[i]);
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
  for (int i = 0; i < kPacketSize; ++i) {
    // An inactive lane's ray is unset; Embree still reads it, so it gets a harmless one.
    const Ray& ray = packet.active[i] ? packet.rays[i] : kIdleRay;
    rays.org_x[i] = ray.origin.x;
    rays.org_y[i] = ray.origin.y;
    rays.org_z[i] = ray.origin.z;
    rays.dir_x[i] = ray.direction.x;
    rays.dir_y[i] = ray.direction.y;
    rays.dir_z[i] = ray.direction.z;
  }
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
  double plane_t[kPacketSize];
  int plane[kPacketSize];
  if (opaque_planes) {
    nearest_planes(plane_sets_[0], rayhit, valid, plane_t, plane);
    for (int i = 0; i < kPacketSize; ++i) {
      // As the plane callback has it: t < t_max, compared in double.
      if ((plane[i] >= 0) & (plane_t[i] < rayhit.ray.tfar[i]))
        rayhit.ray.tfar[i] = static_cast<float>(plane_t[i]);
      else
        plane[i] = -1;
    }
  }
  rtcIntersect16(valid, scene_.get(), &context.embree, &rayhit);
  // A mesh's triangles are read back from memory Embree's traversal did not touch, and a
  // large mesh's are far out of cache: asking for all sixteen at once lets their misses
  // overlap instead of coming one after another.
  for (int i = 0; i < kPacketSize; ++i) {
    const unsigned geometry = rayhit.hit.geomID[i];
    if (!packet.active[i] || geometry == RTC_INVALID_GEOMETRY_ID) continue;
    const GeometryRecord& record = records_[geometry];
    if (record.kind != Kind::triangles) continue;
    const TriangleMesh& mesh = meshes_[record.index];
    const unsigned primitive = rayhit.hit.primID[i];
    __builtin_prefetch(&mesh.triangles[primitive]);
    if (mesh.normals.empty()) continue;
    // Both ends: 36 bytes often straddle two cache lines.
    const auto* normals = reinterpret_cast<const char*>(&mesh.normals[primitive]);
    __builtin_prefetch(normals);
    __builtin_prefetch(normals + sizeof(MeshTriangleNormals) - 1);
  }
  for (int i = 0; i < kPacketSize; ++i) {
    found[i] = false;
    if (!packet.active[i]) continue;
    if (rayhit.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID) {
      finish_hit(packet.rays[i], rayhit.hit.geomID[i], rayhit.hit.primID[i], rayhit.ray.tfar[i],
                 rayhit.hit.u[i], rayhit.hit.v[i], context.t[i], hits[i]);
      found[i] = true;
    } else if (opaque_planes && plane[i] >= 0) {
      finish_hit(packet.rays[i], opaque_planes_geometry_, static_cast<unsigned>(plane[i]),
                 rayhit.ray.tfar[i], 0.0f, 0.0f, plane_t[i], hits[i]);
      found[i] = true;
    }
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
        const Vec3 n = glm::normalize(Vec3(ray.origin) + hit.t * Vec3(ray.direction) -
                                      sphere.world_center);
        hit.position = sphere.world_center + sphere.world_radius * n;
        hit.normal = n;
        hit.shading_normal = n;
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
      const Vec3 p = Vec3(ray.origin) + hit.t * Vec3(ray.direction);
      hit.position = p - glm::dot(p - plane.point, plane.normal) * plane.normal;
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
