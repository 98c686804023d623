// Float RGB images and the tiles they are cut into: the unit of work of the farm.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "common/image/large_buffer.hpp"

namespace tessera {

// A rectangle of pixels; (x, y) is its top-left corner, y = 0 is the top row.
struct TileRect {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;

  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * height; }
  bool operator==(const TileRect&) const = default;
};

// Cuts a width×height image into tiles of edge `tile_size` (the last row and column are
// smaller where the size does not divide), in row-major order.
std::vector<TileRect> split_into_tiles(int width, int height, int tile_size);
// How many tiles split_into_tiles() makes, without making them.
std::uint64_t tile_count(int width, int height, int tile_size);

// Linear float RGB, three floats per pixel, rows top to bottom.
class Image {
 public:
  // For an image whose every pixel is about to be written: its memory is left as the
  // allocator gives it, instead of being zeroed first.
  struct Unset {};

  Image() = default;
  Image(int width, int height);  // black
  Image(int width, int height, Unset);

  int width() const { return width_; }
  int height() const { return height_; }
  std::span<float> pixels() { return pixels_; }
  std::span<const float> pixels() const { return pixels_; }
  float* pixel(int x, int y) { return &pixels_[(static_cast<std::size_t>(y) * width_ + x) * 3]; }
  const float* pixel(int x, int y) const {
    return &pixels_[(static_cast<std::size_t>(y) * width_ + x) * 3];
  }

  // Copies a tile's pixels (tile.width * tile.height RGB triples, row-major) into place.
  void paste(const TileRect& tile, std::span<const float> tile_pixels);

 private:
  int width_ = 0;
  int height_ = 0;
  LargeBuffer<float> pixels_;
};

}  // namespace tessera
