#include "common/image/image.hpp"

#include <algorithm>
#include <stdexcept>

namespace tessera {

std::uint64_t tile_count(int width, int height, int tile_size) {
  if (width <= 0 || height <= 0 || tile_size <= 0)
    throw std::invalid_argument("tile_count: sizes must be positive");
  const auto across = static_cast<std::uint64_t>((width + tile_size - 1) / tile_size);
  const auto down = static_cast<std::uint64_t>((height + tile_size - 1) / tile_size);
  return across * down;
}

std::vector<TileRect> split_into_tiles(int width, int height, int tile_size) {
  if (width <= 0 || height <= 0 || tile_size <= 0)
    throw std::invalid_argument("split_into_tiles: sizes must be positive");
  std::vector<TileRect> tiles;
  for (int y = 0; y < height; y += tile_size)
    for (int x = 0; x < width; x += tile_size)
      tiles.push_back({x, y, std::min(tile_size, width - x), std::min(tile_size, height - y)});
  return tiles;
}

namespace {

// Checked before the pixels are allocated: a negative size would wrap around to a huge one.
std::size_t float_count(int width, int height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("Image: sizes must be positive");
  return static_cast<std::size_t>(width) * height * 3;
}

}  // namespace

Image::Image(int width, int height)
    : width_(width), height_(height), pixels_(float_count(width, height), 0.0f) {}

Image::Image(int width, int height, Unset)
    : width_(width), height_(height), pixels_(float_count(width, height)) {}

void Image::paste(const TileRect& tile, std::span<const float> tile_pixels) {
  if (tile.x < 0 || tile.y < 0 || tile.x + tile.width > width_ || tile.y + tile.height > height_)
    throw std::out_of_range("Image::paste: tile outside the image");
  if (tile_pixels.size() != tile.pixel_count() * 3)
    throw std::invalid_argument("Image::paste: tile pixel count does not match its rectangle");
  const std::size_t row_floats = static_cast<std::size_t>(tile.width) * 3;
  for (int row = 0; row < tile.height; ++row)
    std::copy_n(tile_pixels.data() + row * row_floats, row_floats, pixel(tile.x, tile.y + row));
}

}  // namespace tessera
