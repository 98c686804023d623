// Triangles and meshes as world-space triangle lists. Winding stays counter-clockwise seen
// from outside even under a mirroring transform.
#pragma once

#include "common/scene.hpp"
#include "worker/scene_geometry.hpp"

namespace tessera {

PreparedTriangles triangulate(const Triangle& triangle, const Mat4& transform);
PreparedTriangles triangulate(const Mesh& mesh, const Mat4& transform);

}  // namespace tessera
