#include "tracer/mesh_bvh.hpp"

#include <tuple>

namespace tessera {

TriangleGeometry new_triangle_geometry(const EmbreeDevice& device, const ObjectTriangles& triangles,
                                       const Mat4& transform, std::size_t compact_above) {
  RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  const std::size_t vertex_count = triangles.positions.size();
  const std::size_t triangle_count = triangles.triangles.size();
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
  auto* indices = static_cast<std::uint32_t*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(std::uint32_t), triangle_count));
  if (vertices == nullptr || indices == nullptr) {
    rtcReleaseGeometry(geometry);
    device.check("allocating a triangle mesh");
  }
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const Vec3 p(transform * glm::dvec4(triangles.positions[i], 1.0));
    for (int k = 0; k < 3; ++k) vertices[3 * i + k] = static_cast<float>(p[k]);
  }
  // A mirroring transform turns counter-clockwise into clockwise: two corners trade places.
  const glm::dmat3 linear(transform);
  const bool mirrors = glm::determinant(linear) < 0.0;
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const auto& tri = triangles.triangles[t];
    indices[3 * t] = tri[0];
    indices[3 * t + 1] = mirrors ? tri[2] : tri[1];
    indices[3 * t + 2] = mirrors ? tri[1] : tri[2];
  }
  std::vector<glm::vec3> normals;
  if (!triangles.normals.empty()) {
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    normals.reserve(vertex_count);
    for (const Vec3& n : triangles.normals) normals.emplace_back(glm::normalize(normal_matrix * n));
  }

  TriangleMesh mesh;
  mesh.triangle_count = triangle_count;
  const auto corner = [&](std::size_t t, int k) {
    const float* p = vertices + 3 * static_cast<std::size_t>(indices[3 * t + k]);
    return glm::vec3(p[0], p[1], p[2]);
  };
  if (triangle_count > compact_above) {
    mesh.vertices = vertices;
    mesh.indices = indices;
    mesh.vertex_normals = std::move(normals);
  } else {
    mesh.triangles.resize(triangle_count);
    if (!normals.empty()) mesh.normals.resize(triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
      for (int k = 0; k < 3; ++k) mesh.triangles[t].corners[k] = corner(t, k);
      if (normals.empty()) continue;
      for (int k = 0; k < 3; ++k) mesh.normals[t].corners[k] = normals[indices[3 * t + k]];
    }
    // From the stored floats, in a pass of its own: in the loop above, GCC 12's vectoriser
    // was seen to use the doubles the floats were rounded from (a different normal, and
    // other pixels, than finish_hit() computed from the floats).
    for (MeshTriangle& triangle : mesh.triangles)
      triangle.normal =
          triangle_normal(triangle.corners[0], triangle.corners[1], triangle.corners[2]);
  }
  return {geometry, std::move(mesh)};
}

MeshBvh::MeshBvh(const EmbreeDevice& device, const ObjectTriangles& triangles,
                 std::size_t compact_above)
    : scene_(device) {
  TriangleGeometry built = new_triangle_geometry(device, triangles, Mat4(1.0), compact_above);
  // The instance's mask decides which rays enter; inside, every ray meets every triangle.
  rtcSetGeometryMask(built.geometry, kAnyMask);
  rtcCommitGeometry(built.geometry);
  rtcAttachGeometry(scene_.get(), built.geometry);
  rtcReleaseGeometry(built.geometry);  // the scene holds it, and so its buffers
  device.check("adding a mesh to its own BVH");
  mesh_ = std::move(built.mesh);
  // Robust traversal closes the hairline cracks between neighbouring triangles, as in the
  // scene's own BVH.
  rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene_.get());
  device.check("building a mesh's BVH");
  std::tie(lo_, hi_) = mesh_bounds(mesh_);
}

std::pair<glm::vec3, glm::vec3> mesh_bounds(const TriangleMesh& mesh) {
  glm::vec3 lo(kInfinity);
  glm::vec3 hi(-kInfinity);
  for (std::size_t t = 0; t < mesh.triangle_count; ++t) {
    glm::vec3 corners[3];
    mesh_corners(mesh, t, corners);
    for (const glm::vec3& p : corners) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  }
  return {lo, hi};
}

}  // namespace tessera
