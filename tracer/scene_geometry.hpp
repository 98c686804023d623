// The scene's shapes in world space, registered with Embree. Embree finds which
// primitive a ray hits; the hit itself (distance, point, normals) is then recomputed here
// in double precision from the ray's floats, so that it is exact enough for secondary
// rays and identical on every CPU whatever SIMD path Embree used.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "common/scene/scene.hpp"
#include "tracer/embree_device.hpp"
#include "tracer/ray.hpp"
#include "tracer/tracer_api.hpp"

namespace tessera {

// No object of the scene: Scene::objects never holds this many.
inline constexpr std::uint32_t kNoObject = 0xffffffffu;

// No default values: finish_hit() writes every member, and packets hold sixteen.
struct SurfaceHit {
  double t;
  Vec3 position;
  Vec3 normal;           // geometric, unit: outward for solids, as built for thin shapes
  Vec3 shading_normal;   // unit; interpolated on smooth meshes, else `normal`
  std::uint32_t object;  // index into Scene::objects
  // Which part of the object: a mesh's triangle, a box's face (2·axis, +1 for the face at
  // its max), a cylinder's or a cone's AxialPart; 0 for spheres and planes.
  std::uint32_t primitive;
};

// A secondary ray leaving the surface at `hit`, its origin moved off the surface to the
// side it leaves by.
inline Ray ray_from(const SurfaceHit& hit, const Vec3& direction) {
  return Ray{offset_ray_origin(hit.position, hit.normal, direction),
             glm::vec3(glm::normalize(direction))};
}

// An ellipsoid: the object-space sphere seen through its object-to-world transform.
struct PreparedSphere {
  Vec3 center{0.0};  // object space
  double radius = 1.0;
  Mat4 object_to_world{1.0};
  Mat4 world_to_object{1.0};
  // Set when the transform is a similarity (rotation, uniform scale, translation), as it
  // almost always is: the shape is then a sphere in world space too, and is intersected
  // there without a matrix product per ray.
  bool world_sphere = false;
  Vec3 world_center{0.0};
  double world_radius = 1.0;
};

// A box: axis-aligned in object space, seen through its object-to-world transform. Hits
// name their face as the primitive: 2·axis, +1 for the face at `hi`.
struct PreparedBox {
  Vec3 lo{0.0};  // object space; the frame of the test (world space when `world_box`)
  Vec3 hi{0.0};
  Mat4 world_to_object{1.0};
  Mat4 object_to_world{1.0};
  // Set when the transform only scales along the axes and translates, as it does for most
  // boxes: lo and hi are then world corners, tested without a matrix product per ray.
  bool world_box = false;
  Vec3 face_normals[6];  // world space, unit, outward; by face
};

// A cylinder or a cone: its axis object-space y, seen through its object-to-world
// transform. Hits name their part as the primitive.
enum AxialPart : unsigned { kSide = 0, kBaseCap = 1, kTopCap = 2 };

// A cylinder: its side x² + z² = r² and its caps y = ±half_height, relative to `center`.
struct PreparedCylinder {
  Vec3 center{0.0};  // object space
  double radius = 1.0;
  double half_height = 0.5;
  Mat4 object_to_world{1.0};
  Mat4 world_to_object{1.0};
  glm::dmat3 normal_matrix{1.0};  // the inverse transpose, which keeps outward normals outward
};

// A cone: its side x² + z² = slope2 · y² for -height <= y <= 0 and its base cap y = -height,
// relative to `apex`.
struct PreparedCone {
  Vec3 apex{0.0};       // object space
  double radius = 1.0;  // of the base
  double height = 1.0;
  double slope2 = 1.0;  // (radius / height)²
  double slant = 1.0;   // the side's length from the apex to the base's rim
  Mat4 object_to_world{1.0};
  Mat4 world_to_object{1.0};
  glm::dmat3 normal_matrix{1.0};
};

struct PreparedPlane {
  Vec3 point{0.0};    // world space
  Vec3 normal{0.0};   // world space, unit
  double offset = 0;  // normal · point: the plane is normal · p = offset
};

// A mesh as the tracer reads it after Embree has found a hit: each triangle's corners
// together, in the single precision Embree intersects (so the hit is recomputed on the very
// triangle Embree saw), with its unit geometric normal, worked out once from them in
// double: one cache line per hit instead of one per index and corner.
struct alignas(64) MeshTriangle {
  glm::vec3 corners[3];
  Vec3 normal;  // normalize(cross(v1 - v0, v2 - v0)) of the float corners, in double
};
static_assert(sizeof(MeshTriangle) == 64);
struct MeshTriangleNormals {
  glm::vec3 corners[3];  // unit
};

// Meshes of more triangles than this keep no MeshTriangle copy of their corners beside
// Embree's buffers (64 bytes a triangle, more than Embree's BVH takes): a hit reads its
// corners through Embree's index and vertex buffers instead, and works out the normal, a
// few cache lines more per hit. On a scan of millions of triangles that is a small price
// for a third of the memory; below it, the speed is worth the bytes.
inline constexpr std::size_t kCompactMeshTriangles = std::size_t{1} << 20;

struct TriangleMesh {
  std::vector<MeshTriangle> triangles;
  std::vector<MeshTriangleNormals> normals;  // by triangle; empty for flat shading
  // A compact mesh (above kCompactMeshTriangles) has neither of the above but these: Embree's
  // own buffers, which live as long as its geometry, and its unit normals by vertex.
  const float* vertices = nullptr;         // x, y, z by vertex
  const std::uint32_t* indices = nullptr;  // three by triangle, as Embree holds them
  std::vector<glm::vec3> vertex_normals;   // empty for flat shading
  std::size_t triangle_count = 0;
  bool compact() const { return vertices != nullptr; }
};

// normalize(cross(c1 - c0, c2 - c0)) in double, of a triangle's float corners: a
// MeshTriangle's normal, and a compact mesh's at each hit, by one expression.
inline Vec3 triangle_normal(const glm::vec3& c0, const glm::vec3& c1, const glm::vec3& c2) {
  const Vec3 v0(c0);
  return glm::normalize(glm::cross(Vec3(c1) - v0, Vec3(c2) - v0));
}

// The corners of triangle `t` of a mesh, compact or not: the same floats either way.
inline void mesh_corners(const TriangleMesh& mesh, std::size_t t, glm::vec3 (&out)[3]) {
  if (!mesh.compact()) {
    for (int k = 0; k < 3; ++k) out[k] = mesh.triangles[t].corners[k];
    return;
  }
  for (int k = 0; k < 3; ++k) {
    const float* p = mesh.vertices + 3 * static_cast<std::size_t>(mesh.indices[3 * t + k]);
    out[k] = glm::vec3(p[0], p[1], p[2]);
  }
}

class MeshBvh;  // mesh_bvh.hpp

// A mesh's own BVH (a MeshBvh) as one frame places it: an Embree instance of it, and the
// transform that instance applies, for hits to be rebuilt in object space and then placed.
struct PlacedMesh {
  std::shared_ptr<const MeshBvh> bvh;  // its mesh() is in object space
  Mat4 object_to_world{1.0};
  Mat4 world_to_object{1.0};
  glm::dmat3 normal_matrix{1.0};  // the inverse transpose, which keeps outward normals outward
};

// A triangle list as the scene holds it, in object space, and the transform that places it.
struct ObjectTriangles {
  std::span<const Vec3> positions;
  std::span<const std::array<std::uint32_t, 3>> triangles;  // counter-clockwise from outside
  std::span<const Vec3> normals;                            // unit; empty, or one per position
};

// Every plane of one mask, as a single Embree primitive whose callback tests them all in one
// loop: planes are infinite, so every ray would visit each of them anyway, and one call per
// ray costs less than one per plane.
struct PlaneSet {
  std::vector<PreparedPlane> planes;
  std::vector<std::uint32_t> objects;  // into Scene::objects, by plane
};

// Embree geometry masks: shadow rays first ask whether anything opaque blocks the light,
// and only then walk through the transmissive surfaces. Opaque planes have a bit of their
// own, so that packets of shadow rays can test them outside Embree (occluded()).
inline constexpr unsigned kOpaqueSolidMask = 1u;
inline constexpr unsigned kTransmissiveMask = 2u;
inline constexpr unsigned kOpaquePlaneMask = 4u;
inline constexpr unsigned kOpaqueMask = kOpaqueSolidMask | kOpaquePlaneMask;
inline constexpr unsigned kAnyMask = kOpaqueMask | kTransmissiveMask;

// Embree's intersect context, extended as Embree's tutorials do: the sphere and plane
// callbacks leave here the exact (double) distance of the hit they report for each ray,
// indexed by the ray's id, so that it need not be computed a second time.
struct HitContext {
  RTCIntersectContext embree;
  double t[kPacketSize];
};

// Sixteen rays, each coordinate's lanes side by side as Embree's packets hold them, so that
// filling one of those is a copy and the loops over lanes vectorise. Every lane starts as
// a harmless ray (from the origin along +z), since Embree and those loops read inactive
// lanes too; a lane keeps its last ray when it is turned off.
struct RayPacket {
  float origin[3][kPacketSize];
  float direction[3][kPacketSize];
  bool active[kPacketSize] = {};

  RayPacket() {
    for (int axis = 0; axis < 3; ++axis)
      for (int i = 0; i < kPacketSize; ++i) {
        origin[axis][i] = 0.0f;
        direction[axis][i] = axis == 2 ? 1.0f : 0.0f;
      }
  }
  Ray ray(int i) const {
    return Ray{{origin[0][i], origin[1][i], origin[2][i]},
               {direction[0][i], direction[1][i], direction[2][i]}};
  }
  void set(int i, const Ray& ray) {
    set_origin(i, ray.origin);
    for (int axis = 0; axis < 3; ++axis) direction[axis][i] = ray.direction[axis];
  }
  void set_origin(int i, const glm::vec3& point) {
    for (int axis = 0; axis < 3; ++axis) origin[axis][i] = point[axis];
  }
};

// Fills Embree's packet of sixteen rays (unbounded, under `mask`) and its valid mask.
TESSERA_TRACER_API void load_packet(const RayPacket& packet, int (&valid)[kPacketSize],
                                    RTCRayHit16& rayhit, unsigned mask = kAnyMask);

// Whether the Embree scene holds the opaque planes. Every query here tests them outside
// Embree, on all lanes at once: an infinite plane's box is everywhere, so inside the BVH it
// would be visited by every ray and keep any ray from being culled at the root. The
// benchmark's bare Embree loop, which knows nothing of that, needs them inside.
enum class OpaquePlanes { outside_embree, also_in_embree };

// Exported from the tracer's library member by member: the members only the tracer itself
// calls, such as may_meet_transmissive(), stay hidden (tracer_api.hpp).
class SceneGeometry {
 public:
  // `compact_above`: see kCompactMeshTriangles (the tests set it to 0, to compare).
  // `release`, where given, is `scene` itself: the arrays of each mesh whose material has no
  // texture (which would read its uvs and corners) are freed as soon as Embree holds them,
  // before the BVH is built, so that a big mesh is never held twice at the peak.
  // `previous`, where given, is another frame of the same scene built on the same device:
  // each of its meshes' own BVHs (MeshBvh) is placed again here, with this frame's
  // transform, rather than built again. A frame's meshes are always those of the others.
  TESSERA_TRACER_API SceneGeometry(const Scene& scene, const EmbreeDevice& device,
                                   OpaquePlanes opaque_planes = OpaquePlanes::outside_embree,
                                   std::size_t compact_above = kCompactMeshTriangles,
                                   Scene* release = nullptr,
                                   const SceneGeometry* previous = nullptr);

  // The own BVH of the object's mesh, for a test to see which frames share it; null for an
  // object that is no mesh, or a mesh that has not been placed (mesh_bvh.hpp) in this
  // frame or one before it.
  const MeshBvh* mesh_bvh(std::uint32_t object) const {
    return object < mesh_bvhs_.size() ? mesh_bvhs_[object].get() : nullptr;
  }

  // The closest hit with 0 < t < t_max, if any.
  TESSERA_TRACER_API std::optional<SurfaceHit> intersect(const Ray& ray, float t_max,
                                                         unsigned mask = kAnyMask) const;
  // Whether anything lies on the ray with 0 < t < t_max.
  TESSERA_TRACER_API bool occluded(const Ray& ray, float t_max, unsigned mask = kAnyMask) const;
  // The Embree scene itself, for the benchmark that traces it with nothing around (built
  // with OpaquePlanes::also_in_embree, so that it holds the whole scene).
  RTCScene embree_scene() const { return scene_.get(); }

  // False when the ray certainly meets no transmissive surface with 0 < t < t_max, leaving
  // aside those of the object `left` (kNoObject: none): slab tests against the box around
  // each transmissive object, which spare most shadow rays the walk through transmissive
  // surfaces, and end a walk once nothing is left ahead of it.
  bool may_meet_transmissive(const Ray& ray, float t_max, std::uint32_t left = kNoObject) const;
  // The same for each lane of a packet; false on inactive lanes. Every lane of `t_max` and
  // `left` is read, so that the lanes go through the test together.
  void may_meet_transmissive(const RayPacket& packet, const float (&t_max)[kPacketSize],
                             const std::uint32_t (&left)[kPacketSize],
                             bool (&may)[kPacketSize]) const;
  // The object that a ray leaving `hit` towards `direction` can never meet again, for
  // may_meet_transmissive(): the one hit, where it is convex (a sphere, a box, a cylinder or
  // a cone, under any transform) and the ray leaves its inside there; kNoObject otherwise.
  std::uint32_t left_for_good(const SurfaceHit& hit, const Vec3& direction) const {
    return convex_[hit.object] && glm::dot(hit.normal, direction) > 0.0 ? hit.object : kNoObject;
  }
  // The closest hit of every active ray of a coherent packet (unbounded t). The lanes
  // Embree sees, and so the hits, depend only on the packet's contents; opaque planes are
  // tested here rather than in Embree. found[i] says whether hits[i] was written.
  TESSERA_TRACER_API void intersect(const RayPacket& packet, SurfaceHit (&hits)[kPacketSize],
                                    bool (&found)[kPacketSize]) const;
  // The same for the surfaces under `mask`, with 0 < t < t_max[i] on each lane.
  TESSERA_TRACER_API void intersect(const RayPacket& packet, const float (&t_max)[kPacketSize],
                                    unsigned mask, SurfaceHit (&hits)[kPacketSize],
                                    bool (&found)[kPacketSize]) const;
  // Whether anything under `mask` lies on each active ray of a coherent packet, with
  // 0 < t < t_max[i].
  TESSERA_TRACER_API void occluded(const RayPacket& packet, const float (&t_max)[kPacketSize],
                                   unsigned mask, bool (&blocked)[kPacketSize]) const;

 private:
  // `triangles`: a mesh or a triangle in world space, in the scene's BVH; `placed_mesh`: a
  // mesh's own BVH placed by an instance.
  enum class Kind : std::uint8_t { sphere, box, plane, triangles, cylinder, cone, placed_mesh };
  struct GeometryRecord {
    Kind kind;
    std::uint32_t index;   // into the vector of its kind (for planes: which PlaneSet)
    std::uint32_t object;  // into Scene::objects (for planes: see the PlaneSet)
  };

  // How Embree is to trace a packet of shadow rays: as coherent rays, as all packets are,
  // but in a scene with placed meshes, whose instances Embree 3.13's coherent traversal of
  // shadow packets was seen to loop on forever, next to two analytic shapes
  // (AnimationDeterminism.TexturesAreSharedWithTheGeometry, the textured globe).
  RTCIntersectContextFlags occlusion_flags() const {
    return placed_meshes_.empty() ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT
                                  : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  }
  // Both of the above: `t_max` null for unbounded rays. Its steps follow, each on all lanes
  // (scene_geometry_packet.cpp).
  void intersect(const RayPacket& packet, const float (*t_max)[kPacketSize], unsigned mask,
                 SurfaceHit (&hits)[kPacketSize], bool (&found)[kPacketSize]) const;
  struct PacketQuery;
  struct PacketLanes;
  // Embree's nearest hits, and the opaque planes' where nearer.
  void query_nearest(const RayPacket& packet, const float (*t_max)[kPacketSize], unsigned mask,
                     PacketQuery& query) const;
  // Which geometry and primitive each lane hit, and at what exact distance.
  void identify_lanes(const RayPacket& packet, const PacketQuery& query, PacketLanes& lanes) const;
  // Which lanes hit a world sphere or a plane, and that shape's centre and radius, or point
  // and normal, with each such hit's object; the other lanes' triangles are prefetched.
  void gather_shapes(PacketLanes& lanes, SurfaceHit (&hits)[kPacketSize]) const;
  // The hits on world spheres and planes, on all lanes at once where any lane needs them.
  static void rebuild_spheres_and_planes(const RayPacket& packet, PacketLanes& lanes);
  // Every lane's hit, the shapes not rebuilt on all lanes finished one by one.
  void store_hits(const RayPacket& packet, const PacketQuery& query, const PacketLanes& lanes,
                  SurfaceHit (&hits)[kPacketSize], bool (&found)[kPacketSize]) const;
  void add_sphere(const Sphere& sphere, const Mat4& transform, std::uint32_t object, unsigned mask);
  void add_cylinder(const Cylinder& cylinder, const Mat4& transform, std::uint32_t object,
                    unsigned mask);
  void add_cone(const Cone& cone, const Mat4& transform, std::uint32_t object, unsigned mask);
  void add_box(const Box& box, const Mat4& transform, std::uint32_t object, unsigned mask);
  void add_plane(const Plane& plane, const Mat4& transform, std::uint32_t object,
                 bool transmissive);
  // Fills Embree's buffers straight from the scene's arrays, placed in world space.
  void add_triangles(const ObjectTriangles& triangles, const Mat4& transform, std::uint32_t object,
                     unsigned mask, std::size_t compact_above);
  // An instance of `bvh`, placed by `transform`.
  void add_placed_mesh(std::shared_ptr<const MeshBvh> bvh, const Mat4& transform,
                       std::uint32_t object, unsigned mask);
  void add_analytic_shape(Kind kind, std::uint32_t index, std::uint32_t object, unsigned mask);
  // Lower and upper corners of the box around any record's shape but a plane's.
  std::pair<glm::vec3, glm::vec3> geometry_bounds(const GeometryRecord& record) const;
  // The nearest opaque plane with 0 < t < t_max on the ray, as for a lane of a packet: its
  // index in plane_sets_[0] and distance, or -1 if `mask` leaves them out or none is there.
  int nearest_opaque_plane(const Ray& ray, float t_max, unsigned mask, double& t) const;
  // `exact_t` is the callback's distance, for every shape but triangles.
  void finish_hit(const Ray& ray, unsigned geometry, unsigned primitive, float t, float u, float v,
                  double exact_t, SurfaceHit& hit) const;

  const EmbreeDevice& device_;
  EmbreeScene scene_;
  // By Embree geometry id in scene_: a hit inside a placed mesh is named by its instance's
  // (instID[0]), the geomID being the mesh's in its own BVH.
  std::vector<GeometryRecord> records_;
  // The box around each transmissive object (everything for a plane), or past
  // kListedTransmissive of them, one box around them all, for no object (kNoObject).
  struct TransmissiveBounds {
    glm::vec3 lo;
    glm::vec3 hi;
    std::uint32_t object;
  };
  static constexpr std::size_t kListedTransmissive = 8;
  // Whether may_meet_transmissive() tests `box` for a ray that has left the object `left`:
  // one rule for the single ray and the packets, so that they agree bit for bit.
  static bool tested(const TransmissiveBounds& box, std::uint32_t left) {
    return (box.object != left) | (left == kNoObject);
  }
  std::vector<TransmissiveBounds> transmissive_bounds_;
  std::vector<std::uint8_t> convex_;  // by object: a sphere, a box, a cylinder or a cone
  // Kept at stable addresses: Embree's callbacks hold pointers to these elements.
  std::vector<std::unique_ptr<PreparedSphere>> spheres_;
  std::vector<std::unique_ptr<PreparedBox>> boxes_;
  std::vector<std::unique_ptr<PreparedCylinder>> cylinders_;
  std::vector<std::unique_ptr<PreparedCone>> cones_;
  PlaneSet plane_sets_[2];  // opaque, transmissive
  // The record of plane_sets_[0], after every Embree geometry's (and its Embree geometry
  // id with OpaquePlanes::also_in_embree).
  unsigned opaque_planes_geometry_ = RTC_INVALID_GEOMETRY_ID;
  std::vector<TriangleMesh> meshes_;
  std::vector<PlacedMesh> placed_meshes_;
  std::vector<std::shared_ptr<const MeshBvh>> mesh_bvhs_;  // by object; null for the others
};

namespace geometry_detail {

// The next two rebuild hits for finish_hit() (scene_geometry.cpp) and for the packets' loops
// (scene_geometry_packet.cpp) alike: one definition, so that both give the same bits.

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

// Where the point `p` (relative to a cylinder's or a cone's anchor, in object space) lies
// across its axis, y: its distance from it, and the unit direction away from it (zero on
// the axis itself). Hits snap to the surface by it; texture coordinates take the sine and
// cosine of a longitude from it (surface_uv.cpp).
inline void across_axis(const Vec3& p, double& distance, double& ux, double& uz) {
  distance = std::sqrt(p.x * p.x + p.z * p.z);
  const bool off_axis = distance > 0.0;
  ux = off_axis ? p.x / distance : 0.0;
  uz = off_axis ? p.z / distance : 0.0;
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

// Narrows [t_near, t_far] to the part of the ray along one axis that lies between that
// axis's faces of the box.
[[gnu::always_inline]] inline void narrow_to_slab(float o, float d, float lo, float hi,
                                                  float& t_near, float& t_far, bool& outside) {
  outside |= (d == 0.0f) & ((o < lo) | (o > hi));
  const float t0 = (lo - o) / d;
  const float t1 = (hi - o) / d;
  const bool swap = t0 > t1;
  const float entry = swap ? t1 : t0;
  const float exit = swap ? t0 : t1;
  // Widened by a few ulps so that rounding can only let a ray through, never cut one off.
  t_near = std::max(t_near, entry * (1.0f - 1e-5f));
  t_far = std::min(t_far, exit * (1.0f + 1e-5f));
}

// Whether the ray from o along d may meet the box from lo to hi with 0 < t < t_max. Without
// branches, so that a loop of these over a packet's lanes vectorises and no lane waits on
// another's misprediction; it takes scalars, as GCC vectorises no loop through glm's
// vectors. Where a direction component is zero the quotients are infinite, which leaves the
// interval as it is when the origin lies inside the slab and empties it when it lies
// outside; NaN (the origin on a face) fails every comparison in narrow_to_slab() and leaves it as
// it is too. `outside` also catches the one case the infinities miss, an infinite t_max.
[[gnu::always_inline]] inline bool may_meet_box(float ox, float oy, float oz, float dx, float dy,
                                                float dz, const glm::vec3& lo, const glm::vec3& hi,
                                                float t_max) {
  float t_near = 0.0f;
  float t_far = t_max;
  bool outside = false;
  narrow_to_slab(ox, dx, lo.x, hi.x, t_near, t_far, outside);
  narrow_to_slab(oy, dy, lo.y, hi.y, t_near, t_far, outside);
  narrow_to_slab(oz, dz, lo.z, hi.z, t_near, t_far, outside);
  return !outside & !(t_near > t_far);
}

}  // namespace geometry_detail

// Here rather than in scene_geometry.cpp so that the tracer inlines it (in the shared
// library, GCC kept it out of line and the showcase took 1.1% more instructions).
inline bool SceneGeometry::may_meet_transmissive(const Ray& ray, float t_max,
                                                 std::uint32_t left) const {
  bool may = false;
  for (const TransmissiveBounds& box : transmissive_bounds_)
    may |= tested(box, left) &
           geometry_detail::may_meet_box(ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x,
                                         ray.direction.y, ray.direction.z, box.lo, box.hi, t_max);
  return may;
}

}  // namespace tessera
