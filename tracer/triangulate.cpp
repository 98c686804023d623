#include "tracer/triangulate.hpp"

namespace tessera {
namespace {

constexpr std::array<std::uint32_t, 3> kOneTriangle[1] = {{0, 1, 2}};

}  // namespace

ObjectTriangles triangles_of(const Triangle& triangle) {
  std::span<const Vec3> normals;
  if (triangle.normals) normals = *triangle.normals;
  return {triangle.vertices, kOneTriangle, normals};
}

ObjectTriangles triangles_of(const Mesh& mesh) {
  return {mesh.positions, mesh.triangles, mesh.normals};
}

}  // namespace tessera
