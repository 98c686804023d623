// Mesh-file reading throughput: one grid of triangles written as OBJ, binary PLY and glb,
// each read back through read_model_file() as `tessera render` reads a scene's files.
// Prints one line per format: format, bytes, triangles, median seconds, MB/s, Mtriangles/s.
// Usage: tessera_mesh_files_bench [TRIANGLES (default 2000000)] [RUNS (default 3)]
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "bench/grid_mesh.hpp"
#include "bench/median.hpp"
#include "common/mesh_files/folder_scene_files.hpp"

namespace {

namespace fs = std::filesystem;
using namespace tessera::bench;

}  // namespace

int main(int argc, char** argv) {
  const long triangles = argc > 1 ? std::atol(argv[1]) : 2000000;
  const int runs = argc > 2 ? std::atoi(argv[2]) : 3;
  if (triangles < 2 || runs < 1) {
    std::fprintf(stderr, "usage: tessera_mesh_files_bench [TRIANGLES] [RUNS]\n");
    return 2;
  }
  const Grid grid = grid_of(triangles);
  const fs::path dir =
      fs::temp_directory_path() / ("tessera-mesh-bench-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::pair<const char*, std::string> files[] = {
      {"grid.obj", obj(grid)}, {"grid.ply", ply(grid)}, {"grid.glb", glb(grid)}};
  std::printf("format bytes triangles seconds MB/s Mtriangles/s\n");
  for (const auto& [name, bytes] : files) {
    write_file(dir / name, bytes);
    tessera::MeshFileRequest request;
    request.file = name;
    request.format = *tessera::mesh_format_of(name);
    request.max_triangles = request.limit_max_triangles = 1u << 30;
    std::vector<double> seconds;
    std::size_t read = 0;
    for (int r = 0; r < runs; ++r) {
      const auto start = std::chrono::steady_clock::now();
      const tessera::Model model = tessera::read_model_file(dir / name, request);
      seconds.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      read = model.triangles();
    }
    const double s = tessera::bench::median(seconds);
    std::printf("%s %zu %zu %.3f %.1f %.2f\n", fs::path(name).extension().c_str() + 1, bytes.size(),
                read, s, bytes.size() / s / 1e6, read / s / 1e6);
  }
  fs::remove_all(dir);
  return 0;
}
