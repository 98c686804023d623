#include "worker/renderer.hpp"

#include <algorithm>
#include <stdexcept>

#include <xmmintrin.h>

#include "worker/pixel_sampler.hpp"

namespace tessera {
namespace {

// Denormals flushed to zero on the rendering thread, as Embree recommends: they only ever
// arise in rays that contribute nothing visible, and cost a hundred cycles each. Every
// worker sets the same mode, so the bits of a pixel stay the same everywhere.
class FlushDenormals {
 public:
  FlushDenormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFlushToZero | kDenormalsAreZero); }
  ~FlushDenormals() { _mm_setcsr(saved_); }
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;

 private:
  static constexpr unsigned kFlushToZero = 0x8000;
  static constexpr unsigned kDenormalsAreZero = 0x0040;
  unsigned saved_;
};

}  // namespace

Renderer::Renderer(Scene scene)
    : scene_(std::move(scene)),
      geometry_(scene_, device_),
      tracer_(scene_, geometry_),
      camera_(scene_.camera, scene_.width, scene_.height) {}

RayCounts Renderer::render_tile(const TileRect& tile, std::span<float> out) const {
  if (out.size() != tile.pixel_count() * 3)
    throw std::invalid_argument("render_tile: output buffer does not match the tile");
  return render_tile(tile, out, static_cast<std::size_t>(tile.width) * 3);
}

RayCounts Renderer::render_tile(const TileRect& tile, std::span<float> out,
                                std::size_t row_stride) const {
  if (tile.x < 0 || tile.y < 0 || tile.width <= 0 || tile.height <= 0 ||
      tile.x + tile.width > scene_.width || tile.y + tile.height > scene_.height)
    throw std::out_of_range("render_tile: tile outside the image");
  const std::size_t row = static_cast<std::size_t>(tile.width) * 3;
  if (row_stride < row || out.size() < (tile.height - 1) * row_stride + row)
    throw std::invalid_argument("render_tile: output buffer does not hold the tile");

  const FlushDenormals flush_denormals;
  const int samples = scene_.render.samples_per_pixel;
  RayCounts counts;
  // The mean of the samples. Dividing by a power of two and multiplying by its reciprocal
  // round alike (the reciprocal is exact), and the product is cheaper: 1, 4, 16 and 64
  // samples are the common counts.
  const bool power_of_two = (samples & (samples - 1)) == 0;
  const double inverse_samples = 1.0 / samples;
  const auto divide_by_samples = [&](const Color& sum) {
    return power_of_two ? sum * inverse_samples : sum / static_cast<double>(samples);
  };
  // Primary rays go out as packets of a 4x4 block of pixels aligned to the image, never to
  // the tile: a block cut by the tile's edge is traced whole and only its pixels inside the
  // tile are kept, so that Embree always sees the same packet for a pixel and its hit
  // cannot depend on how the image was tiled.
  // Lanes outside the image are never traced: they keep this value, which goes only into
  // sums that are never written out.
  Color colors[kPacketSize];
  for (Color& color : colors) color = Color(0.0);
  const int x_end = tile.x + tile.width;
  const int y_end = tile.y + tile.height;
  for (int block_y = tile.y - tile.y % kPacketSide; block_y < y_end; block_y += kPacketSide) {
    for (int block_x = tile.x - tile.x % kPacketSide; block_x < x_end; block_x += kPacketSide) {
      // By channel, lanes side by side: added to channel by channel and read back as a
      // pixel's three, never loaded wider than they were stored (which would stall).
      double sums[3][kPacketSize];
      bool in_tile[kPacketSize];
      RayPacket packet;
      // Most blocks lie wholly inside the tile, and so inside the image.
      const bool whole = block_x >= tile.x && block_x + kPacketSide <= x_end && block_y >= tile.y &&
                         block_y + kPacketSide <= y_end;
      for (int channel = 0; channel < 3; ++channel)
        for (int i = 0; i < kPacketSize; ++i) sums[channel][i] = 0.0;
      for (int i = 0; i < kPacketSize; ++i) {
        if (whole) {
          packet.active[i] = in_tile[i] = true;
          continue;
        }
        const int x = block_x + i % kPacketSide;
        const int y = block_y + i / kPacketSide;
        packet.active[i] = x < scene_.width && y < scene_.height;
        in_tile[i] = x >= tile.x && x < x_end && y >= tile.y && y < y_end;
      }
      // Row by row of the block, only its pixels inside the tile.
      const int column_begin = std::max(block_x, tile.x) - block_x;
      const int column_end = std::min(block_x + kPacketSide, x_end) - block_x;
      const int row_begin = std::max(block_y, tile.y) - block_y;
      const int row_end = std::min(block_y + kPacketSide, y_end) - block_y;
      const auto first_pixel = [&](int row) {
        return out.data() + static_cast<std::size_t>(block_y + row - tile.y) * row_stride +
               3 * static_cast<std::size_t>(block_x + column_begin - tile.x);
      };
      // The block's pixels lie in as many rows of the image as the block has, each of which
      // may be far from the cache (a whole image is tens of megabytes): asked for now, for
      // writing, they arrive while the block is traced, and the stores below do not wait.
      for (int row = row_begin; row < row_end; ++row) {
        const float* begin = first_pixel(row);
        __builtin_prefetch(begin, 1);
        __builtin_prefetch(begin + 3 * (column_end - column_begin) - 1, 1);
      }
      // Each lane's pixel, and with several samples the rotation of its sequence, once for
      // the block: the rays of a sample are then loops over plain arrays, which vectorise.
      // The lanes outside the image get rays too, which are never traced.
      double pixel_x[kPacketSize];
      double pixel_y[kPacketSize];
      double rotation_x[kPacketSize];
      double rotation_y[kPacketSize];
      for (int i = 0; i < kPacketSize; ++i) {
        const int x = block_x + i % kPacketSide;
        const int y = block_y + i / kPacketSide;
        pixel_x[i] = x;
        pixel_y[i] = y;
        const SampleRotation rotation = samples > 1 ? sample_rotation(x, y) : SampleRotation{};
        rotation_x[i] = rotation.x;
        rotation_y[i] = rotation.y;
      }
      const glm::vec3 eye = camera_.origin();
      for (int axis = 0; axis < 3; ++axis)
        for (int i = 0; i < kPacketSize; ++i) packet.origin[axis][i] = eye[axis];
      for (int s = 0; s < samples; ++s) {
        // sample_offset()'s positions.
        double x[kPacketSize];
        double y[kPacketSize];
        if (samples == 1) {
          for (int i = 0; i < kPacketSize; ++i) x[i] = pixel_x[i] + 0.5;
          for (int i = 0; i < kPacketSize; ++i) y[i] = pixel_y[i] + 0.5;
        } else {
          for (int i = 0; i < kPacketSize; ++i)
            x[i] = pixel_x[i] + sample_fraction(rotation_x[i], kSampleStepX, s);
          for (int i = 0; i < kPacketSize; ++i)
            y[i] = pixel_y[i] + sample_fraction(rotation_y[i], kSampleStepY, s);
        }
        camera_.directions_through(x, y, packet.direction);
        tracer_.trace_packet(packet, 0, in_tile, colors, counts);
        // Every lane, in tile or not: a loop without a condition stores whole vectors, which
        // the loads below can take straight from the store, where masked stores make them wait.
        for (int channel = 0; channel < 3; ++channel)
          for (int i = 0; i < kPacketSize; ++i) sums[channel][i] += colors[i][channel];
      }
      for (int row = row_begin; row < row_end; ++row) {
        float* pixel = first_pixel(row);
        for (int column = column_begin; column < column_end; ++column, pixel += 3) {
          const int i = row * kPacketSide + column;
          const Color value = divide_by_samples(Color(sums[0][i], sums[1][i], sums[2][i]));
          pixel[0] = static_cast<float>(value.r);
          pixel[1] = static_cast<float>(value.g);
          pixel[2] = static_cast<float>(value.b);
        }
      }
    }
  }
  return counts;
}

}  // namespace tessera
