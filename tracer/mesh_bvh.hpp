// A mesh's own BVH, built once over its object-space triangles, which an Embree instance
// places in the world. A frame of an animation in which the mesh moves places the same
// MeshBvh again, with the frame's transform: its top-level BVH holds one box for the mesh
// instead of all its triangles, and the mesh is never built again.
#pragma once

#include <cstddef>
#include <utility>

#include "tracer/embree_device.hpp"
#include "tracer/scene_geometry.hpp"

namespace tessera {

// A mesh is placed by an instance of its own BVH when its transform is not the identity and
// it has this many triangles or more (or a frame before it placed it). The others go into
// the scene's own BVH in world space, built again in every frame in which anything moves:
// for a small mesh that costs less than the instance's second traversal costs every ray,
// and a mesh where the scene's data put it (the identity) is traced a tenth faster there.
// The rule reads only the frame, so that a frame and the still scene of its values build
// alike, bit for bit.
inline constexpr std::size_t kInstancedMeshTriangles = 256;

// An Embree triangle geometry, not yet committed, of `triangles` placed by `transform` (each
// corner in double, rounded once to the floats Embree intersects), and the mesh the hits
// read back from it. Its buffers live as long as the geometry does.
struct TriangleGeometry {
  RTCGeometry geometry;
  TriangleMesh mesh;
};
TriangleGeometry new_triangle_geometry(const EmbreeDevice& device, const ObjectTriangles& triangles,
                                       const Mat4& transform, std::size_t compact_above);

// The box around a mesh's corners: floats already, so their extremes bound it exactly.
std::pair<glm::vec3, glm::vec3> mesh_bounds(const TriangleMesh& mesh);

class MeshBvh {
 public:
  // `compact_above`: see kCompactMeshTriangles.
  MeshBvh(const EmbreeDevice& device, const ObjectTriangles& triangles, std::size_t compact_above);

  RTCScene scene() const { return scene_.get(); }
  // In object space: the corners are those the instance's rays meet.
  const TriangleMesh& mesh() const { return mesh_; }
  // The box around the triangles, in object space.
  const glm::vec3& lo() const { return lo_; }
  const glm::vec3& hi() const { return hi_; }

 private:
  EmbreeScene scene_;
  TriangleMesh mesh_;
  glm::vec3 lo_{0.0f};
  glm::vec3 hi_{0.0f};
};

}  // namespace tessera
