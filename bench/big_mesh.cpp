// A big mesh on a worker (issue 25, part 5): a grid of TRIANGLES triangles as a binary PLY
// or glb, from its file to the first tile, against Embree building the same BVH from arrays
// already in memory. Each mode runs in a process of its own, so that its peak RSS is its own:
//   tessera_big_mesh_bench write TRIANGLES DIR   writes DIR/grid.ply and DIR/grid.glb
//   tessera_big_mesh_bench embree FILE           reads FILE's arrays (not timed), then times
//       rtcCommitScene on them as SceneGeometry builds (robust flag); prints the seconds, the
//       bytes of the arrays (positions and indices, as floats and 32-bit integers; the grid
//       has no normals) and the bytes Embree holds after the build (its BVH)
//   tessera_big_mesh_bench tessera FILE          times what a worker does: the scene parsed
//       with the file read through FolderSceneFiles, the Renderer built (geometry, BVH), and
//       one 32 x 32 tile rendered; prints the seconds of each and the process's peak RSS
//       growth over its RSS before the file was read
// Lines are "key value" pairs, for bench/run. Like tessera-worker, the program starts itself
// again with glibc's malloc on transparent huge pages (common/image/huge_page_malloc.hpp).
#include <atomic>
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

#include <embree3/rtcore.h>

#include "bench/coordinator_load/server_process.hpp"
#include "bench/grid_mesh.hpp"
#include "common/image/huge_page_malloc.hpp"
#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scene/scene_parser.hpp"
#include "tracer/renderer.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A "Vm...:" field of this process's /proc status, in bytes.
std::uint64_t status_bytes(const char* field) {
  return static_cast<std::uint64_t>(tessera::load::process_status_kib(::getpid(), field)) * 1024;
}

tessera::Model read(const fs::path& file) {
  tessera::MeshFileRequest request;
  request.file = file.filename().string();
  request.format = *tessera::mesh_format_of(request.file);
  request.max_triangles = request.limit_max_triangles = 1u << 30;
  return tessera::read_model_file(file, request);
}

std::atomic<std::int64_t> embree_bytes{0};
bool count_embree(void*, ssize_t bytes, bool) {
  embree_bytes += bytes;
  return true;
}

int embree_alone(const fs::path& file) {
  const tessera::Model model = read(file);
  const tessera::Mesh& mesh = model.parts.at(0).mesh;
  std::vector<float> positions;
  positions.reserve(mesh.positions.size() * 3);
  for (const auto& p : mesh.positions)
    for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(p[k]));
  std::vector<std::uint32_t> indices;
  indices.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());

  RTCDevice device = rtcNewDevice(nullptr);
  rtcSetDeviceMemoryMonitorFunction(device, count_embree, nullptr);
  const std::int64_t before = embree_bytes;
  const auto start = Clock::now();
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                             positions.data(), 0, 3 * sizeof(float), mesh.positions.size());
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices.data(),
                             0, 3 * sizeof(std::uint32_t), mesh.triangles.size());
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene);
  const double seconds = since(start);
  std::printf("triangles %zu\nseconds %.3f\narray_bytes %zu\nbvh_bytes %lld\n",
              mesh.triangles.size(), seconds,
              positions.size() * sizeof(float) + indices.size() * sizeof(std::uint32_t),
              static_cast<long long>(embree_bytes - before));
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return 0;
}

int tessera_path(const fs::path& file) {
  const std::uint64_t rss_before = status_bytes("VmRSS");
  const std::string scene_text = R"({
    "image": {"width": 256, "height": 256},
    "camera": {"eye": [0.5, 1.2, 1.6], "look_at": [0.5, 0, 0.5], "fov_y": 45},
    "lights": [{"type": "point", "position": [2, 3, 2], "intensity": 1}],
    "objects": [{"type": "mesh", "file": ")" +
                                 file.filename().string() + R"("}]})";
  const tessera::FolderSceneFiles files(file.parent_path());
  const auto start = Clock::now();
  tessera::Scene scene = tessera::parse_scene_text(scene_text, tessera::Limits{}, {}, &files);
  const double load = since(start);
  const auto build_start = Clock::now();
  const tessera::Renderer renderer(std::move(scene));
  const double build = since(build_start);
  const auto tile_start = Clock::now();
  std::vector<float> pixels(32 * 32 * 3);
  renderer.render_tile({112, 112, 32, 32}, pixels);
  const double tile = since(tile_start);
  std::printf("load_seconds %.3f\nbuild_seconds %.3f\ntile_seconds %.3f\nseconds %.3f\n", load,
              build, tile, since(start));
  std::printf("peak_rss_growth %llu\n",
              static_cast<unsigned long long>(status_bytes("VmHWM") - rss_before));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // As tessera-worker starts (worker_main.cpp), both sides alike.
  tessera::restart_with_huge_page_malloc(argv);
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "write" && argc == 4) {
    const tessera::bench::Grid grid = tessera::bench::grid_of(std::atol(argv[2]));
    fs::create_directories(argv[3]);
    tessera::bench::write_file(fs::path(argv[3]) / "grid.ply", tessera::bench::ply(grid));
    tessera::bench::write_file(fs::path(argv[3]) / "grid.glb", tessera::bench::glb(grid));
    return 0;
  }
  if (mode == "embree" && argc == 3) return embree_alone(argv[2]);
  if (mode == "tessera" && argc == 3) return tessera_path(argv[2]);
  std::fprintf(stderr,
               "usage: tessera_big_mesh_bench write TRIANGLES DIR | embree FILE | tessera FILE\n");
  return 2;
}
