#include "server/farm/tile_order.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace tessera {

std::vector<int> centre_first_order(std::span<const TileRect> tiles, int width, int height) {
  // Doubled coordinates keep centres integral, so ties are exact, not rounding noise.
  std::vector<std::int64_t> distance(tiles.size());
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const std::int64_t dx = 2 * std::int64_t{tiles[i].x} + tiles[i].width - width;
    const std::int64_t dy = 2 * std::int64_t{tiles[i].y} + tiles[i].height - height;
    distance[i] = dx * dx + dy * dy;
  }
  std::vector<int> order(tiles.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return distance[a] < distance[b]; });
  return order;
}

}  // namespace tessera
