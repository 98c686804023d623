#include "tracer/local_render.hpp"

#include <atomic>
#include <mutex>
#include <span>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace tessera {

LocalRenderResult render_local(const Renderer& renderer, int threads, int tile_size) {
  const Scene& scene = renderer.scene();
  const std::vector<TileRect> tiles = split_into_tiles(
      scene.width, scene.height, tile_size > 0 ? tile_size : scene.render.tile_size);
  // Unset: the tiles below cover every pixel.
  LocalRenderResult result{Image(scene.width, scene.height, Image::Unset{}), {}};
  std::mutex counts_mutex;

  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        RayCounts local;
                        // Straight into the image: tiles never overlap, so this needs
                        // no lock, and no copy.
                        const std::span<float> pixels = result.image.pixels();
                        const std::size_t stride = static_cast<std::size_t>(scene.width) * 3;
                        for (std::size_t i = range.begin(); i != range.end(); ++i) {
                          const TileRect& tile = tiles[i];
                          const std::size_t first =
                              static_cast<std::size_t>(tile.y) * stride + 3 * tile.x;
                          local += renderer.render_tile(tile, pixels.subspan(first), stride);
                        }
                        std::lock_guard lock(counts_mutex);
                        result.rays += local;
                      });
  });
  return result;
}

}  // namespace tessera
