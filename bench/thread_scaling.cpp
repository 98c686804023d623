// The tracer's scaling from 1 to 2 threads: render_local(), the path `tessera render`
// takes from its "tracing" clock, run on one Renderer with 1 and with 2 threads
// alternately, in one process that does nothing else meanwhile. (`tessera render -o X.exr`
// loads OpenImageIO on its main thread while other threads trace, which shares the cores
// with the 2-thread render but not with the 1-thread one, so its own "tracing" figure
// measures that too; a PNG, written with libpng, loads nothing.) Prints the median of each
// and their ratio.
//
// Usage: tessera_thread_scaling SCENE.json SPP RUNS
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/median.hpp"
#include "common/scene/scene_parser.hpp"
#include "tracer/local_render.hpp"

namespace {

using tessera::bench::median;

double timed_render(const tessera::Renderer& renderer, int threads) {
  const auto start = std::chrono::steady_clock::now();
  const auto result = tessera::render_local(renderer, threads);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (result.rays.total() == 0) throw std::runtime_error("the render traced no rays");
  return seconds;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s SCENE.json SPP RUNS\n", argv[0]);
    return 2;
  }
  try {
    nlohmann::json document = tessera::read_json_file(argv[1]);
    document["render"]["samples_per_pixel"] = std::stoi(argv[2]);
    const int runs = std::stoi(argv[3]);
    const tessera::Renderer renderer(tessera::parse_scene(document));
    std::vector<double> one, two;
    for (int run = 0; run < runs; ++run) {
      // Alternating which goes first, as bench/run does between processes.
      if (run % 2 == 0) {
        one.push_back(timed_render(renderer, 1));
        two.push_back(timed_render(renderer, 2));
      } else {
        two.push_back(timed_render(renderer, 2));
        one.push_back(timed_render(renderer, 1));
      }
    }
    const double t1 = median(one), t2 = median(two);
    std::printf("1 thread %.3f s, 2 threads %.3f s, ratio %.3f\n", t1, t2, t1 / t2);
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "tessera_thread_scaling: %s\n", error.what());
    return 1;
  }
}
