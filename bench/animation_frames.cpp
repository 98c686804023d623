// The scene build of each frame of an animation in which only the camera moves, on a mesh
// of a million triangles: the first frame builds the BVH, the later ones should cost next
// to nothing (issue 27). Against that, the same frame built whole, as a worker without the
// frame before would build it.
//   tessera_animation_frames_bench TRIANGLES DIR
// writes DIR/grid.ply and DIR/scene.json and prints "name value" lines:
//   triangles, first_build_seconds, next_build_seconds (the median over frames 2 to 6),
//   whole_build_seconds, shared (1 when every later frame reused the first one's geometry).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/grid_mesh.hpp"
#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scene_frames.hpp"
#include "common/scene_parser.hpp"
#include "worker/local_render.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kFrames = 6;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string animated_scene() {
  nlohmann::json keys = nlohmann::json::array();
  for (int frame = 1; frame <= kFrames; ++frame)
    keys.push_back({frame, {0.5 + 0.1 * frame, 1.2, 1.6}});
  const nlohmann::json scene = {
      {"image", {{"width", 64}, {"height", 36}}},
      {"animation", {{"frames", {1, kFrames}}, {"fps", 24}}},
      {"camera",
       {{"eye", {{"keys", keys}, {"interpolation", "smooth"}}}, {"look_at", {0.5, 0, 0.5}}}},
      {"lights", {{{"type", "point"}, {"position", {0.5, 3, 0.5}}}}},
      {"objects", {{{"type", "mesh"}, {"file", "grid.ply"}}}}};
  return scene.dump();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: tessera_animation_frames_bench TRIANGLES DIR\n");
    return 2;
  }
  const fs::path dir = argv[2];
  fs::create_directories(dir);
  const tessera::bench::Grid grid = tessera::bench::grid_of(std::atol(argv[1]));
  tessera::bench::write_file(dir / "grid.ply", tessera::bench::ply(grid));
  const std::string text = animated_scene();
  tessera::bench::write_file(dir / "scene.json", text);
  const tessera::FolderSceneFiles files(dir);

  auto start = Clock::now();
  tessera::SceneFrames frames(text, tessera::Limits{}, {}, &files);
  auto renderer = std::make_unique<tessera::Renderer>(frames.take_first());
  const double first_build = seconds_since(start);
  const auto triangles = 2L * grid.side * grid.side;
  tessera::render_local(*renderer);

  std::vector<double> next_builds;
  bool shared = true;
  for (int frame = 2; frame <= kFrames; ++frame) {
    start = Clock::now();
    auto next = std::make_unique<tessera::Renderer>(frames.at(frame, renderer->scene()), *renderer);
    next_builds.push_back(seconds_since(start));
    shared = shared && next->shares_geometry_with(*renderer);
    tessera::render_local(*next);
    renderer = std::move(next);
  }
  std::sort(next_builds.begin(), next_builds.end());

  renderer.reset();
  start = Clock::now();
  const tessera::Renderer whole(
      tessera::parse_scene_text(text, tessera::Limits{}, {}, &files, kFrames));
  const double whole_build = seconds_since(start);

  std::printf("triangles %ld\n", triangles);
  std::printf("first_build_seconds %.6f\n", first_build);
  std::printf("next_build_seconds %.6f\n", next_builds[next_builds.size() / 2]);
  std::printf("whole_build_seconds %.6f\n", whole_build);
  std::printf("shared %d\n", shared ? 1 : 0);
  return shared ? 0 : 1;
}
