// SceneGeometry's queries for packets of sixteen rays: the nearest hits, rebuilt in double
// for all lanes at once where they lie on world spheres and planes, and occlusion.
#include <cstdint>

#include "tracer/analytic_shapes.hpp"
#include "tracer/mesh_bvh.hpp"
#include "tracer/scene_geometry.hpp"

namespace tessera {
namespace {

using geometry_detail::plane_hit;
using geometry_detail::world_sphere_hit;

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

// How a lane's hit is rebuilt: on all lanes at once for world spheres and planes, by
// finish_hit() for the other shapes.
enum class Rebuilt : std::uint8_t { none, sphere, plane, other };

}  // namespace

// Embree's answer for a packet, with the opaque planes' tested beside it.
struct SceneGeometry::PacketQuery {
  HitContext context;
  alignas(64) int valid[kPacketSize];
  alignas(64) RTCRayHit16 rayhit;
  double plane_t[kPacketSize];
  int plane[kPacketSize];  // in plane_sets_[0], -1 where none is nearer than Embree's hit
};

// Each lane's hit on its way from the query to a SurfaceHit: its shape, and what the
// rebuilding of a sphere's or a plane's hit reads and writes. Lanes without a sphere or a
// plane keep zeros in the shapes' arrays, on which the rebuilds run harmlessly.
struct SceneGeometry::PacketLanes {
  Rebuilt rebuilt[kPacketSize];
  unsigned geometry[kPacketSize];
  unsigned primitive[kPacketSize];
  double t[kPacketSize];
  double anchor[3][kPacketSize];  // a sphere's centre, a point on a plane
  double radius[kPacketSize];
  double normal[3][kPacketSize];  // a plane's
  double sphere_normal[3][kPacketSize];
  double sphere_point[3][kPacketSize];
  double plane_point[3][kPacketSize];
};

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
  PacketQuery query;
  query_nearest(packet, t_max, mask, query);
  // Hits on world spheres and on planes, nearly all hits in most scenes, are rebuilt for all
  // sixteen lanes at once, in loops the compiler vectorises: lane by lane, each sphere's
  // square root and division made the next lane wait (a fifth of the ray-casting
  // benchmark's time went there). First each lane's shape is gathered; other hits go
  // through finish_hit() afterwards.
  PacketLanes lanes;
  identify_lanes(packet, query, lanes);
  gather_shapes(lanes, hits);
  rebuild_spheres_and_planes(packet, lanes);
  store_hits(packet, query, lanes, hits, found);
}

void SceneGeometry::query_nearest(const RayPacket& packet, const float (*t_max)[kPacketSize],
                                  unsigned mask, PacketQuery& query) const {
  HitContext& context = query.context;
  RTCRayHit16& rayhit = query.rayhit;
  rtcInitIntersectContext(&context.embree);
  context.embree.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // see occlusion_flags()
  // Opaque planes are tested here, on all lanes at once (see OpaquePlanes); Embree then
  // looks only for something nearer than each lane's plane.
  const bool opaque_planes =
      (mask & kOpaquePlaneMask) != 0 && opaque_planes_geometry_ != RTC_INVALID_GEOMETRY_ID;
  load_packet(packet, query.valid, rayhit, opaque_planes ? mask & ~kOpaquePlaneMask : mask);
  if (t_max != nullptr)
    for (int i = 0; i < kPacketSize; ++i) rayhit.ray.tfar[i] = (*t_max)[i];
  for (int i = 0; i < kPacketSize; ++i) query.plane_t[i] = 0.0;
  for (int i = 0; i < kPacketSize; ++i) query.plane[i] = -1;
  if (opaque_planes) {
    nearest_planes(plane_sets_[0], rayhit, query.valid, query.plane_t, query.plane);
    for (int i = 0; i < kPacketSize; ++i) {
      // As the plane callback has it: t < t_max, compared in double. Without branches, so
      // that the lanes go through together.
      const bool nearer = (query.plane[i] >= 0) & (query.plane_t[i] < rayhit.ray.tfar[i]);
      rayhit.ray.tfar[i] = nearer ? static_cast<float>(query.plane_t[i]) : rayhit.ray.tfar[i];
      query.plane[i] = nearer ? query.plane[i] : -1;
    }
  }
  // The callbacks set the lanes they hit; the others are read too, by identify_lanes().
  for (double& t : context.t) t = 0.0;
  rtcIntersect16(query.valid, scene_.get(), &context.embree, &rayhit);
}

void SceneGeometry::identify_lanes(const RayPacket& packet, const PacketQuery& query,
                                   PacketLanes& lanes) const {
  const RTCHit16& hit16 = query.rayhit.hit;
  // Each lane's hit, Embree's or else the opaque plane's, and the arrays the lanes without
  // a sphere or a plane keep at zero: without branches, so that every lane is done at once.
  for (int i = 0; i < kPacketSize; ++i) {
    const bool by_plane = (hit16.geomID[i] == RTC_INVALID_GEOMETRY_ID) & (query.plane[i] >= 0);
    // A hit inside a placed mesh names the instance first (see GeometryRecord).
    const unsigned instance = hit16.instID[0][i];
    const unsigned embree =
        instance != RTC_INVALID_GEOMETRY_ID ? instance : static_cast<unsigned>(hit16.geomID[i]);
    lanes.geometry[i] = by_plane ? opaque_planes_geometry_ : embree;
    lanes.primitive[i] = by_plane ? static_cast<unsigned>(query.plane[i]) : hit16.primID[i];
    const bool hit = packet.active[i] & (lanes.geometry[i] != RTC_INVALID_GEOMETRY_ID);
    lanes.t[i] = !hit ? 0.0 : by_plane ? query.plane_t[i] : query.context.t[i];
    lanes.rebuilt[i] = hit ? Rebuilt::other : Rebuilt::none;
  }
  for (int i = 0; i < kPacketSize; ++i) lanes.radius[i] = 0.0;
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 0; i < kPacketSize; ++i) lanes.anchor[axis][i] = lanes.normal[axis][i] = 0.0;
}

void SceneGeometry::gather_shapes(PacketLanes& lanes, SurfaceHit (&hits)[kPacketSize]) const {
  for (int i = 0; i < kPacketSize; ++i) {
    if (lanes.rebuilt[i] == Rebuilt::none) continue;
    const unsigned primitive = lanes.primitive[i];
    const GeometryRecord& record = records_[lanes.geometry[i]];
    if (record.kind == Kind::sphere && spheres_[record.index]->world_sphere) {
      const PreparedSphere& sphere = *spheres_[record.index];
      lanes.rebuilt[i] = Rebuilt::sphere;
      hits[i].object = record.object;
      for (int axis = 0; axis < 3; ++axis) lanes.anchor[axis][i] = sphere.world_center[axis];
      lanes.radius[i] = sphere.world_radius;
    } else if (record.kind == Kind::plane) {
      const PlaneSet& set = plane_sets_[record.index];
      const PreparedPlane& prepared = set.planes[primitive];
      lanes.rebuilt[i] = Rebuilt::plane;
      hits[i].object = set.objects[primitive];
      for (int axis = 0; axis < 3; ++axis) {
        lanes.anchor[axis][i] = prepared.point[axis];
        lanes.normal[axis][i] = prepared.normal[axis];
      }
    } else {
      if (record.kind != Kind::triangles && record.kind != Kind::placed_mesh) continue;
      lanes.t[i] = 0.0;  // no callback's: finish_hit() recomputes a triangle's
      // A mesh's triangles are read back from memory Embree's traversal did not touch, and
      // a large mesh's are far out of cache: asking for all sixteen before finish_hit()
      // reads the first lets their misses overlap instead of coming one after another.
      const TriangleMesh& mesh = record.kind == Kind::triangles
                                     ? meshes_[record.index]
                                     : placed_meshes_[record.index].bvh->mesh();
      if (mesh.compact()) {  // its corners are found through the indices, one step later
        __builtin_prefetch(mesh.indices + 3 * static_cast<std::size_t>(primitive));
        continue;
      }
      __builtin_prefetch(&mesh.triangles[primitive]);
      if (mesh.normals.empty()) continue;
      // Both ends: 36 bytes often straddle two cache lines.
      const auto* normals = reinterpret_cast<const char*>(&mesh.normals[primitive]);
      __builtin_prefetch(normals);
      __builtin_prefetch(normals + sizeof(MeshTriangleNormals) - 1);
    }
  }
}

void SceneGeometry::rebuild_spheres_and_planes(const RayPacket& packet, PacketLanes& lanes) {
  // Each kind's rebuild runs on all sixteen lanes, the lanes of other kinds on harmless
  // zeros, and only where some lane needs it: packets of secondary rays often hold a few
  // active lanes, all of one kind.
  bool any_sphere = false;
  bool any_plane = false;
  for (int i = 0; i < kPacketSize; ++i) {
    any_sphere = any_sphere | (lanes.rebuilt[i] == Rebuilt::sphere);
    any_plane = any_plane | (lanes.rebuilt[i] == Rebuilt::plane);
  }
  const auto& o = packet.origin;
  const auto& d = packet.direction;
  const auto& anchor = lanes.anchor;
  if (any_sphere)
    for (int i = 0; i < kPacketSize; ++i) {
      double n[3];
      double p[3];
      world_sphere_hit(o[0][i], o[1][i], o[2][i], d[0][i], d[1][i], d[2][i], lanes.t[i],
                       anchor[0][i], anchor[1][i], anchor[2][i], lanes.radius[i], n, p);
      for (int axis = 0; axis < 3; ++axis) {
        lanes.sphere_normal[axis][i] = n[axis];
        lanes.sphere_point[axis][i] = p[axis];
      }
    }
  if (any_plane)
    for (int i = 0; i < kPacketSize; ++i) {
      double p[3];
      plane_hit(o[0][i], o[1][i], o[2][i], d[0][i], d[1][i], d[2][i], lanes.t[i], anchor[0][i],
                anchor[1][i], anchor[2][i], lanes.normal[0][i], lanes.normal[1][i],
                lanes.normal[2][i], p);
      for (int axis = 0; axis < 3; ++axis) lanes.plane_point[axis][i] = p[axis];
    }
}

void SceneGeometry::store_hits(const RayPacket& packet, const PacketQuery& query,
                               const PacketLanes& lanes, SurfaceHit (&hits)[kPacketSize],
                               bool (&found)[kPacketSize]) const {
  const RTCRayHit16& rayhit = query.rayhit;
  for (int i = 0; i < kPacketSize; ++i) {
    const Rebuilt rebuilt = lanes.rebuilt[i];
    found[i] = rebuilt != Rebuilt::none;
    if (rebuilt == Rebuilt::other)
      finish_hit(packet.ray(i), lanes.geometry[i], lanes.primitive[i], rayhit.ray.tfar[i],
                 rayhit.hit.u[i], rayhit.hit.v[i], lanes.t[i], hits[i]);
    if ((rebuilt != Rebuilt::sphere) & (rebuilt != Rebuilt::plane)) continue;
    const bool sphere = rebuilt == Rebuilt::sphere;
    // Each member stored from registers: copying the normal just stored into the shading
    // normal would load it back before its pieces reached the cache, and stall.
    // The lane's own array is chosen before it is read: the other may not have been written.
    const auto pick = [&](const double(&a)[3][kPacketSize], const double(&b)[3][kPacketSize]) {
      const auto& chosen = sphere ? a : b;
      return Vec3(chosen[0][i], chosen[1][i], chosen[2][i]);
    };
    const Vec3 n = pick(lanes.sphere_normal, lanes.normal);
    SurfaceHit& hit = hits[i];
    hit.primitive = 0;
    hit.t = lanes.t[i];
    hit.position = pick(lanes.sphere_point, lanes.plane_point);
    hit.normal = n;
    hit.shading_normal = n;
  }
}

void SceneGeometry::occluded(const RayPacket& packet, const float (&t_max)[kPacketSize],
                             unsigned mask, bool (&blocked)[kPacketSize]) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = occlusion_flags();
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

}  // namespace tessera
