// Triangles and meshes as triangle lists in object space, without a copy: views of the
// scene's own arrays, which SceneGeometry places in world space as it fills Embree's buffers.
#pragma once

#include "common/scene/scene.hpp"
#include "tracer/scene_geometry.hpp"

namespace tessera {

ObjectTriangles triangles_of(const Triangle& triangle);
ObjectTriangles triangles_of(const Mesh& mesh);

}  // namespace tessera
