// The benchmarks' test mesh: a rippled grid of triangles, written as OBJ, binary PLY or glb
// (bench/mesh_files.cpp, bench/big_mesh.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "examples/gltf_bytes.hpp"

namespace tessera::bench {

using gltf_bytes::append;

// A side × side grid of squares, two triangles each, rippled so that no triangle is flat
// with its neighbour.
struct Grid {
  int side;
  float x(int i) const { return static_cast<float>(i) / side; }
  float y(int i, int j) const { return 0.05f * static_cast<float>(((i * 7 + j * 13) % 11)) / 11.f; }
  std::uint32_t index(int i, int j) const { return static_cast<std::uint32_t>(j * (side + 1) + i); }
};

inline void write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string obj(const Grid& g) {
  std::string out;
  char line[96];
  for (int j = 0; j <= g.side; ++j)
    for (int i = 0; i <= g.side; ++i) {
      std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", g.x(i), g.y(i, j), g.x(j));
      out += line;
    }
  for (int j = 0; j < g.side; ++j)
    for (int i = 0; i < g.side; ++i) {
      std::snprintf(line, sizeof line, "f %u %u %u\nf %u %u %u\n", g.index(i, j) + 1,
                    g.index(i, j + 1) + 1, g.index(i + 1, j) + 1, g.index(i + 1, j) + 1,
                    g.index(i, j + 1) + 1, g.index(i + 1, j + 1) + 1);
      out += line;
    }
  return out;
}

inline void vertices_and_indices(const Grid& g, std::string& vertices, std::string& indices,
                                 bool ply_faces) {
  for (int j = 0; j <= g.side; ++j)
    for (int i = 0; i <= g.side; ++i) {
      append(vertices, g.x(i));
      append(vertices, g.y(i, j));
      append(vertices, g.x(j));
    }
  for (int j = 0; j < g.side; ++j)
    for (int i = 0; i < g.side; ++i)
      for (const auto& t :
           {std::array{g.index(i, j), g.index(i, j + 1), g.index(i + 1, j)},
            std::array{g.index(i + 1, j), g.index(i, j + 1), g.index(i + 1, j + 1)}}) {
        if (ply_faces) append(indices, std::uint8_t{3});
        for (const std::uint32_t v : t) append(indices, v);
      }
}

inline std::string ply(const Grid& g) {
  const std::size_t vertices = static_cast<std::size_t>(g.side + 1) * (g.side + 1);
  const std::size_t faces = 2ull * g.side * g.side;
  std::string out =
      "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertices) +
      "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
      std::to_string(faces) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  std::string indices;
  vertices_and_indices(g, out, indices, true);
  return out + indices;
}

inline std::string glb(const Grid& g) {
  std::string bin, indices;
  vertices_and_indices(g, bin, indices, false);
  const std::size_t vertex_bytes = bin.size();
  bin += indices;
  const std::size_t vertices = vertex_bytes / 12;
  std::string json =
      "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
      "\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":[{\"attributes\":"
      "{\"POSITION\":0},\"indices\":1}]}],\"accessors\":[{\"bufferView\":0,"
      "\"componentType\":5126,\"count\":" +
      std::to_string(vertices) +
      ",\"type\":\"VEC3\"},{\"bufferView\":1,\"componentType\":5125,\"count\":" +
      std::to_string(indices.size() / 4) +
      ",\"type\":\"SCALAR\"}],\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,"
      "\"byteLength\":" +
      std::to_string(vertex_bytes) +
      "},{\"buffer\":0,\"byteOffset\":" + std::to_string(vertex_bytes) +
      ",\"byteLength\":" + std::to_string(indices.size()) +
      "}],\"buffers\":[{\"byteLength\":" + std::to_string(bin.size()) + "}]}";
  return gltf_bytes::glb(std::move(json), std::move(bin));
}

// The grid with at most `triangles` triangles, and as many as that allows.
inline Grid grid_of(long triangles) {
  Grid grid{1};
  while (2L * (grid.side + 1) * (grid.side + 1) <= triangles) ++grid.side;
  return grid;
}

}  // namespace tessera::bench
