#include "worker/renderer.hpp"

#include <stdexcept>

#include "worker/pixel_sampler.hpp"

namespace tessera {

Renderer::Renderer(Scene scene)
    : scene_(std::move(scene)),
      geometry_(scene_, device_),
      tracer_(scene_, geometry_),
      camera_(scene_.camera, scene_.width, scene_.height) {}

RayCounts Renderer::render_tile(const TileRect& tile, std::span<float> out) const {
  if (tile.x < 0 || tile.y < 0 || tile.width <= 0 || tile.height <= 0 ||
      tile.x + tile.width > scene_.width || tile.y + tile.height > scene_.height)
    throw std::out_of_range("render_tile: tile outside the image");
  if (out.size() != tile.pixel_count() * 3)
    throw std::invalid_argument("render_tile: output buffer does not match the tile");

  const int samples = scene_.render.samples_per_pixel;
  RayCounts counts;
  float* pixel = out.data();
  for (int y = tile.y; y < tile.y + tile.height; ++y) {
    for (int x = tile.x; x < tile.x + tile.width; ++x, pixel += 3) {
      Color sum(0.0);
      for (int s = 0; s < samples; ++s) {
        const SampleOffset offset = sample_offset(x, y, s, samples);
        sum += tracer_.trace(camera_.ray_through(x + offset.x, y + offset.y), 0, counts);
      }
      const Color value = sum / static_cast<double>(samples);
      pixel[0] = static_cast<float>(value.r);
      pixel[1] = static_cast<float>(value.g);
      pixel[2] = static_cast<float>(value.b);
    }
  }
  return counts;
}

}  // namespace tessera
