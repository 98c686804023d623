#include "common/mesh_files/mesh_builder.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

namespace tessera {
namespace {

constexpr std::uint32_t unused = std::numeric_limits<std::uint32_t>::max();

std::optional<Vec3> unit(const Vec3& v) {
  const double length = glm::length(v);
  if (!(length > 0.0) || !std::isfinite(length)) return std::nullopt;
  return v / length;
}

// For each position, the first position at the same point: where a file gives one point
// several uvs (a texture's seam), the reader made a position of each, and smooth normals
// must not crease there.
std::vector<std::uint32_t> weld_points(const std::vector<Vec3>& positions, bool split) {
  std::vector<std::uint32_t> point(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) point[i] = static_cast<std::uint32_t>(i);
  if (!split) return point;
  struct Bits {
    std::size_t operator()(const Vec3& v) const {
      std::uint64_t h = 0;
      for (int k = 0; k < 3; ++k) {
        std::uint64_t b;
        std::memcpy(&b, &v[k], sizeof b);
        h = (h ^ b) * 0x9e3779b97f4a7c15ull;
      }
      return static_cast<std::size_t>(h ^ (h >> 29));
    }
  };
  std::unordered_map<Vec3, std::uint32_t, Bits> first;
  first.reserve(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i)
    point[i] = first.try_emplace(positions[i], static_cast<std::uint32_t>(i)).first->second;
  return point;
}

// Each point's normal as the sum of its faces' cross products, which weighs each face by
// its area; a point whose faces cancel out takes its first face's normal.
std::vector<Vec3> smooth_normals(const Mesh& mesh) {
  const std::vector<std::uint32_t> point = weld_points(mesh.positions, !mesh.uvs.empty());
  std::vector<Vec3> sums(mesh.positions.size(), Vec3(0.0));
  std::vector<Vec3> first(mesh.positions.size(), Vec3(0.0));
  for (const auto& t : mesh.triangles) {
    const Vec3 face = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                                 mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (const std::uint32_t corner : t) {
      const std::uint32_t i = point[corner];
      if (sums[i] == Vec3(0.0) && first[i] == Vec3(0.0)) first[i] = face;
      sums[i] += face;
    }
  }
  std::vector<Vec3> normals(sums.size());
  for (std::size_t i = 0; i < sums.size(); ++i) {
    const std::uint32_t p = point[i];
    auto n = unit(sums[p]);
    if (!n) n = unit(first[p]);
    normals[i] = n ? *n : Vec3(0.0, 1.0, 0.0);
  }
  return normals;
}

}  // namespace

std::optional<Mesh> finish_mesh(RawMesh raw, NormalsMode mode) {
  Mesh mesh;
  std::vector<std::uint32_t> renumbered(raw.positions.size(), unused);
  mesh.triangles.reserve(raw.triangles.size());
  for (const auto& t : raw.triangles) {
    if (is_degenerate(raw.positions[t[0]], raw.positions[t[1]], raw.positions[t[2]])) continue;
    std::array<std::uint32_t, 3> kept{};
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& to = renumbered[t[k]];
      if (to == unused) {
        to = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(raw.positions[t[k]]);
      }
      kept[k] = to;
    }
    mesh.triangles.push_back(kept);
  }
  if (mesh.triangles.empty()) return std::nullopt;
  if (raw.uvs.size() == raw.positions.size()) {
    mesh.uvs.resize(mesh.positions.size());
    for (std::size_t i = 0; i < renumbered.size(); ++i) {
      if (renumbered[i] == unused) continue;
      const Uv uv = raw.uvs[i];
      if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {  // as a file without uvs
        mesh.uvs.clear();
        break;
      }
      mesh.uvs[renumbered[i]] = uv;
    }
  }

  if (mode == NormalsMode::smooth) {
    mesh.normals = smooth_normals(mesh);
  } else if (mode == NormalsMode::file && raw.normals.size() == raw.positions.size()) {
    mesh.normals.resize(mesh.positions.size());
    for (std::size_t i = 0; i < renumbered.size(); ++i) {
      if (renumbered[i] == unused) continue;
      const auto n = unit(raw.normals[i]);
      if (!n) {  // one unusable normal: the part is shaded flat, as if the file had none
        mesh.normals.clear();
        break;
      }
      mesh.normals[renumbered[i]] = *n;
    }
  }
  return mesh;
}

void add_polygon(std::span<const std::uint32_t> corners,
                 std::vector<std::array<std::uint32_t, 3>>& triangles) {
  for (std::size_t i = 2; i < corners.size(); ++i)
    triangles.push_back({corners[0], corners[i - 1], corners[i]});
}

}  // namespace tessera
