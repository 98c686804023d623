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

PreparedTriangles triangulate(const Box& box, const Mat4& transform) {
  std::vector<Vec3> corners(8);
  for (int i = 0; i < 8; ++i)
    corners[i] = Vec3((i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y,
                      (i & 4) ? box.max.z : box.min.z);
  std::vector<std::array<std::uint32_t, 3>> triangles;
  for (int axis = 0; axis < 3; ++axis) {
    const int b = (axis + 1) % 3;
    const int c = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      // Walking the face's corners in (b, c) order circles +axis counter-clockwise, which
      // faces outward on the max side; the min side is walked the other way round.
      std::array<std::uint32_t, 4> quad{};
      const int cycle[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int k = 0; k < 4; ++k)
        quad[k] = (side << axis) | (cycle[k][0] << b) | (cycle[k][1] << c);
      if (side == 0) std::swap(quad[1], quad[3]);
      triangles.push_back({quad[0], quad[1], quad[2]});
      triangles.push_back({quad[0], quad[2], quad[3]});
    }
  }
  return to_world(std::move(corners), std::move(triangles), {}, transform);
}

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
