// Tessera's ray-casting rate against Embree's own, on the same Embree scene.
//
// The scene is reduced to ray casting (max_depth 0, no lights, so no shadow rays), and at
// the chosen size one primary ray per pixel is traced two ways, alternately:
//   - tessera: render_local(), the path `tessera render` takes: tiles on a TBB arena, camera
//     rays, hit reconstruction in double, shading, the image;
//   - embree: a bare loop over the same camera rays in 4x4 packets through rtcIntersect16
//     with the coherent flag, keeping nothing but a checksum of the hit ids, on an Embree
//     scene that holds every shape (planes as user geometry with Tessera's callbacks).
// It prints the median rate of each and their ratio.
//
// Usage: tessera_embree_rays SCENE.json WIDTH HEIGHT THREADS RUNS
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <nlohmann/json.hpp>

#include "bench/median.hpp"
#include "common/scene/scene_parser.hpp"
#include "tracer/embree_device.hpp"
#include "tracer/local_render.hpp"
#include "tracer/scene_geometry.hpp"

namespace {

using tessera::bench::median;

using tessera::kPacketSide;
using tessera::kPacketSize;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One packet per 4x4 block of pixels, rows of blocks spread over the arena's threads.
// `embree` holds the whole scene, its planes included.
std::uint64_t trace_bare(const tessera::Renderer& renderer, RTCScene embree,
                         tbb::task_arena& arena) {
  const tessera::Scene& scene = renderer.scene();
  const int block_rows = (scene.height + kPacketSide - 1) / kPacketSide;
  return arena.execute([&] {
    return tbb::parallel_reduce(
        tbb::blocked_range<int>(0, block_rows), std::uint64_t{0},
        [&](const tbb::blocked_range<int>& rows, std::uint64_t sum) {
          // The context type the scene's sphere and plane callbacks expect.
          tessera::HitContext context;
          rtcInitIntersectContext(&context.embree);
          context.embree.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
          alignas(64) int valid[kPacketSize];
          alignas(64) RTCRayHit16 rayhit;
          for (int row = rows.begin(); row != rows.end(); ++row)
            for (int bx = 0; bx < scene.width; bx += kPacketSide) {
              // The camera rays as render_tile() makes them, all lanes at once.
              tessera::RayPacket packet;
              double px[kPacketSize];
              double py[kPacketSize];
              for (int i = 0; i < kPacketSize; ++i) {
                const int x = bx + i % kPacketSide;
                const int y = row * kPacketSide + i / kPacketSide;
                packet.active[i] = x < scene.width && y < scene.height;
                px[i] = x + 0.5;
                py[i] = y + 0.5;
              }
              const glm::vec3 eye = renderer.camera().origin();
              for (int axis = 0; axis < 3; ++axis)
                for (int i = 0; i < kPacketSize; ++i) packet.origin[axis][i] = eye[axis];
              renderer.camera().directions_through(px, py, packet.direction);
              tessera::load_packet(packet, valid, rayhit);
              rtcIntersect16(valid, embree, &context.embree, &rayhit);
              // A missed lane's primID is whatever the last hit there left.
              for (int i = 0; i < kPacketSize; ++i)
                if (valid[i] && rayhit.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID)
                  sum += rayhit.hit.geomID[i] + rayhit.hit.primID[i];
            }
          return sum;
        },
        [](std::uint64_t a, std::uint64_t b) { return a + b; });
  });
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: %s SCENE.json WIDTH HEIGHT THREADS RUNS\n", argv[0]);
    return 2;
  }
  try {
    nlohmann::json document = tessera::read_json_file(argv[1]);
    document["image"]["width"] = std::stoi(argv[2]);
    document["image"]["height"] = std::stoi(argv[3]);
    document["render"]["samples_per_pixel"] = 1;
    document["render"]["max_depth"] = 0;
    document["lights"] = nlohmann::json::array();
    const int threads = std::stoi(argv[4]);
    const int runs = std::stoi(argv[5]);
    // The meshes kept: the bare loop builds its own geometry from the renderer's scene.
    const tessera::Renderer renderer(tessera::parse_scene(document, tessera::Limits::none()),
                                     {tessera::kCompactMeshTriangles, true});
    // Embree's own scene of the same shapes: the renderer's leaves the opaque planes out,
    // since it tests them itself.
    const tessera::EmbreeDevice device;
    const tessera::SceneGeometry whole(renderer.scene(), device,
                                       tessera::OpaquePlanes::also_in_embree);
    const double rays = static_cast<double>(renderer.scene().width) * renderer.scene().height;

    tbb::task_arena arena(threads);
    std::vector<double> tessera_rates;
    std::vector<double> embree_rates;
    std::uint64_t checksum = 0;
    for (int run = 0; run < runs; ++run) {
      auto start = std::chrono::steady_clock::now();
      const auto result = tessera::render_local(renderer, threads);
      tessera_rates.push_back(static_cast<double>(result.rays.total()) / seconds_since(start));
      start = std::chrono::steady_clock::now();
      checksum += trace_bare(renderer, whole.embree_scene(), arena);
      embree_rates.push_back(rays / seconds_since(start));
    }
    const double tessera_rate = median(tessera_rates) / 1e6;
    const double embree_rate = median(embree_rates) / 1e6;
    // The checksum keeps the compiler from dropping the bare loop's results.
    std::printf("tessera %.2f Mrays/s, embree %.2f Mrays/s, ratio %.3f (checksum %llu)\n",
                tessera_rate, embree_rate, tessera_rate / embree_rate,
                static_cast<unsigned long long>(checksum % 1000));
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "tessera_embree_rays: %s\n", error.what());
    return 1;
  }
}
