// What every mesh reader shares: a mesh as a file gives it, made into a Mesh the tracer can
// trust (no degenerate triangles, no unused positions, unit normals or none).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "common/scene/scene_files.hpp"

namespace tessera {

struct RawMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  // empty, or one per position (any length, even zero)
  std::vector<std::array<std::uint32_t, 3>> triangles;  // indices below positions.size()
  std::vector<Uv> uvs;  // empty, or one per position (OBJ's v up, as Mesh::uvs)
};

// Drops degenerate triangles and the positions no triangle uses, and chooses the shading
// normals by `mode`: the file's where every kept position has a usable one (else none),
// none, or the area-weighted average of the faces around each point (positions that a uv
// seam split count as one point). Keeps the uvs. Nothing when no triangle is left.
std::optional<Mesh> finish_mesh(RawMesh raw, NormalsMode mode);

// Triangles of a convex polygon as a fan from its first corner: `corners` are indices.
void add_polygon(std::span<const std::uint32_t> corners,
                 std::vector<std::array<std::uint32_t, 3>>& triangles);

}  // namespace tessera
