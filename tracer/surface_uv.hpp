// Where a hit lies in its surface's texture space (docs/scene-format.md, "Texture
// coordinates"), for the shapes' own conventions: longitude and latitude on spheres, two
// axes on planes, a square per face on boxes, the vertices' uvs on triangles and meshes.
#pragma once

#include "common/scene/scene.hpp"
#include "tracer/scene_geometry.hpp"

namespace tessera {

struct SurfaceUv {
  glm::dvec2 uv;  // u to the right, v up the image
  Vec3 dpdu;      // how the world-space point moves with u, and with v: the footprint's
  Vec3 dpdv;      // way from world space into the texture's (zero where undefined)
};

// `world_to_object` is the inverse of object.transform; `hit` is a hit on `object`.
SurfaceUv surface_uv(const Object& object, const Mat4& world_to_object, const SurfaceHit& hit);

}  // namespace tessera
