#include "worker/local_render.hpp"

#include <atomic>
#include <mutex>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace tessera {

LocalRenderResult render_local(const Renderer& renderer, int threads, int tile_size) {
  const Scene& scene = renderer.scene();
  const std::vector<TileRect> tiles = split_into_tiles(
      scene.width, scene.height, tile_size > 0 ? tile_size : scene.render.tile_size);
  LocalRenderResult result{Image(scene.width, scene.height), {}};
  std::mutex counts_mutex;

  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        std::vector<float> buffer;
                        RayCounts local;
                        for (std::size_t i = range.begin(); i != range.end(); ++i) {
                          buffer.resize(tiles[i].pixel_count() * 3);
                          local += renderer.render_tile(tiles[i], buffer);
                          // Tiles never overlap, so pasting needs no lock.
                          result.image.paste(tiles[i], buffer);
                        }
                        std::lock_guard lock(counts_mutex);
                        result.rays += local;
                      });
  });
  return result;
}

}  // namespace tessera
