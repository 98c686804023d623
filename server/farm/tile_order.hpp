// The order in which a job's tiles are handed out.
#pragma once

#include <span>
#include <vector>

#include "common/image/image.hpp"

namespace tessera {

// Tile indices, nearest tile centre to the image centre first (ties: lower index first),
// so that the interesting part of a picture appears first in a live preview.
std::vector<int> centre_first_order(std::span<const TileRect> tiles, int width, int height);

}  // namespace tessera
