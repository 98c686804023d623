// The scene build of each frame of an animation in which only the camera moves, on a mesh
// of a million triangles: the first frame builds the BVH, the later ones should cost next
// to nothing (issue 27). Against that, the same frame built whole, as a worker without the
// frame before would build it. Then the same mesh turning (a track in its transform): a
// later frame reads the whole text again, mesh file and all, and builds a BVH of its own
// over its objects, but places the mesh's own BVH, built for the first frame, again.
//   tessera_animation_frames_bench TRIANGLES DIR
// writes DIR/grid.ply, DIR/scene.json and DIR/turning.json and prints "name value" lines:
//   triangles, first_build_seconds, next_build_seconds (the median over frames 2 to 6),
//   whole_build_seconds, shared (1 when every later frame reused the first one's geometry);
//   turning_read_seconds and turning_build_seconds (the medians over frames 2 to 6 of
//   reading the frame's scene and of building its geometry), turning_whole_build_seconds,
//   turning_placed (1 when every later frame placed the first one's mesh BVH).
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
#include "common/scene/scene_frames.hpp"
#include "common/scene/scene_parser.hpp"
#include "tracer/local_render.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kFrames = 6;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The camera-only animation, or with `turning` the mesh turning under a still camera.
std::string animated_scene(bool turning) {
  nlohmann::json keys = nlohmann::json::array();
  for (int frame = 1; frame <= kFrames; ++frame)
    keys.push_back({frame, {0.5 + 0.1 * frame, 1.2, 1.6}});
  nlohmann::json scene = {
      {"image", {{"width", 64}, {"height", 36}}},
      {"animation", {{"frames", {1, kFrames}}, {"fps", 24}}},
      {"camera",
       {{"eye", {{"keys", keys}, {"interpolation", "smooth"}}}, {"look_at", {0.5, 0, 0.5}}}},
      {"lights", {{{"type", "point"}, {"position", {0.5, 3, 0.5}}}}},
      {"objects", {{{"type", "mesh"}, {"file", "grid.ply"}}}}};
  if (turning) {
    scene["camera"]["eye"] = {0.5, 1.2, 1.6};
    scene["objects"][0]["transform"] = {
        {{"rotate",
          {{"axis", {0, 1, 0}},
           {"degrees", {{"keys", {{1, 10}, {kFrames, 60}}}, {"interpolation", "linear"}}}}}}};
  }
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
  const std::string text = animated_scene(false);
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

  // The last frame of `scene_text` read and built whole, with no frame before it; the
  // renderer of the frames before is let go first, as a fresh process would have none.
  const auto whole_build_of = [&](const std::string& scene_text) {
    renderer.reset();
    const auto whole_start = Clock::now();
    const tessera::Renderer whole(
        tessera::parse_scene_text(scene_text, tessera::Limits{}, {}, &files, kFrames));
    return seconds_since(whole_start);
  };
  const double whole_build = whole_build_of(text);

  // The mesh turning: each later frame's reading and building apart.
  const std::string turning_text = animated_scene(true);
  tessera::bench::write_file(dir / "turning.json", turning_text);
  tessera::SceneFrames turning(turning_text, tessera::Limits{}, {}, &files);
  renderer = std::make_unique<tessera::Renderer>(turning.take_first());
  tessera::render_local(*renderer);
  std::vector<double> turning_reads;
  std::vector<double> turning_builds;
  bool placed = true;
  for (int frame = 2; frame <= kFrames; ++frame) {
    start = Clock::now();
    tessera::Scene scene = turning.at(frame, renderer->scene());
    turning_reads.push_back(seconds_since(start));
    start = Clock::now();
    auto next = std::make_unique<tessera::Renderer>(std::move(scene), *renderer);
    turning_builds.push_back(seconds_since(start));
    placed = placed && next->geometry().mesh_bvh(0) != nullptr &&
             next->geometry().mesh_bvh(0) == renderer->geometry().mesh_bvh(0);
    tessera::render_local(*next);
    renderer = std::move(next);
  }
  std::sort(turning_reads.begin(), turning_reads.end());
  std::sort(turning_builds.begin(), turning_builds.end());
  const double turning_whole_build = whole_build_of(turning_text);

  std::printf("triangles %ld\n", triangles);
  std::printf("first_build_seconds %.6f\n", first_build);
  std::printf("next_build_seconds %.6f\n", next_builds[next_builds.size() / 2]);
  std::printf("whole_build_seconds %.6f\n", whole_build);
  std::printf("shared %d\n", shared ? 1 : 0);
  std::printf("turning_read_seconds %.6f\n", turning_reads[turning_reads.size() / 2]);
  std::printf("turning_build_seconds %.6f\n", turning_builds[turning_builds.size() / 2]);
  std::printf("turning_whole_build_seconds %.6f\n", turning_whole_build);
  std::printf("turning_placed %d\n", placed ? 1 : 0);
  return shared && placed ? 0 : 1;
}
