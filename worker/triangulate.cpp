#include "worker/triangulate.hpp"

#include <utility>

namespace tessera {
namespace {

// Applies the transform to a triangle list given in object space.
PreparedTriangles to_world(std::vector<Vec3> positions,
                           std::vector<std::array<std::uint32_t, 3>> triangles,
                           std::vector<Vec3> normals, const Mat4& transform) {
  for (Vec3& p : positions) p = Vec3(transform * glm::dvec4(p, 1.0));
  const glm::dmat3 linear(transform);
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
  for (Vec3& n : normals) n = glm::normalize(normal_matrix * n);
  // A mirroring transform turns counter-clockwise into clockwise.
  if (glm::determinant(linear) < 0.0)
    for (auto& t : triangles) std::swap(t[1], t[2]);
  return {std::move(positions), std::move(triangles), std::move(normals)};
}

}  // namespace

PreparedTriangles triangulate(const Triangle& triangle, const Mat4& transform) {
  std::vector<Vec3> normals;
  if (triangle.normals) normals.assign(triangle.normals->begin(), triangle.normals->end());
  return to_world({triangle.vertices.begin(), triangle.vertices.end()}, {{0, 1, 2}},
                  std::move(normals), transform);
}

PreparedTriangles triangulate(const Mesh& mesh, const Mat4& transform) {
  return to_world(mesh.positions, mesh.triangles, mesh.normals, transform);
}

}  // namespace tessera
