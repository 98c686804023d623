#include "tracer/renderer.hpp"

#include <algorithm>
#include <stdexcept>

#include <xmmintrin.h>

#include "tracer/pixel_sampler.hpp"

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

// The mean of a pixel's samples. Dividing by a power of two and multiplying by its
// reciprocal round alike (the reciprocal is exact), and the product is cheaper: 1, 4, 16
// and 64 samples are the common counts.
class SampleMean {
 public:
  explicit SampleMean(int samples)
      : samples_(samples),
        power_of_two_((samples & (samples - 1)) == 0),
        inverse_samples_(1.0 / samples) {}

  Color operator()(const Color& sum) const {
    return power_of_two_ ? sum * inverse_samples_ : sum / static_cast<double>(samples_);
  }

 private:
  int samples_;
  bool power_of_two_;
  double inverse_samples_;
};

// A block of the image's 4x4 grid, and the part of it inside the tile: its columns and rows
// counted from the block's corner, ends excluded.
struct Block {
  int x;
  int y;
  int column_begin;
  int column_end;
  int row_begin;
  int row_end;
};

Block block_at(const TileRect& tile, int block_x, int block_y) {
  const int x_end = tile.x + tile.width;
  const int y_end = tile.y + tile.height;
  return {block_x,
          block_y,
          std::max(block_x, tile.x) - block_x,
          std::min(block_x + kPacketSide, x_end) - block_x,
          std::max(block_y, tile.y) - block_y,
          std::min(block_y + kPacketSide, y_end) - block_y};
}

// Where render_tile() stores the tile: rows `row_stride` floats apart from its first pixel.
struct TileOutput {
  TileRect tile;
  float* first;
  std::size_t row_stride;

  // The first of the block's pixels inside the tile on the block's row `row`.
  float* row_start(const Block& block, int row) const {
    return first + static_cast<std::size_t>(block.y + row - tile.y) * row_stride +
           3 * static_cast<std::size_t>(block.x + block.column_begin - tile.x);
  }
};

// The block's pixels lie in as many rows of the image as the block has, each of which may
// be far from the cache (a whole image is tens of megabytes): asked for before the block is
// traced, for writing, they arrive meanwhile, and store_block() does not wait for them.
void prefetch_block(const TileOutput& out, const Block& block) {
  for (int row = block.row_begin; row < block.row_end; ++row) {
    const float* begin = out.row_start(block, row);
    __builtin_prefetch(begin, 1);
    __builtin_prefetch(begin + 3 * (block.column_end - block.column_begin) - 1, 1);
  }
}

// Which lanes get traced (their pixel lies in the image) and which are kept (it lies in the
// tile too).
void mark_lanes(const TileRect& tile, int width, int height, int block_x, int block_y,
                bool (&active)[kPacketSize], bool (&in_tile)[kPacketSize]) {
  const int x_end = tile.x + tile.width;
  const int y_end = tile.y + tile.height;
  // Most blocks lie wholly inside the tile, and so inside the image.
  const bool whole = block_x >= tile.x && block_x + kPacketSide <= x_end && block_y >= tile.y &&
                     block_y + kPacketSide <= y_end;
  for (int i = 0; i < kPacketSize; ++i) {
    if (whole) {
      active[i] = in_tile[i] = true;
      continue;
    }
    const int x = block_x + i % kPacketSide;
    const int y = block_y + i / kPacketSide;
    active[i] = x < width && y < height;
    in_tile[i] = x >= tile.x && x < x_end && y >= tile.y && y < y_end;
  }
}

// Each lane's pixel, and with several samples the rotation of its sequence, once for the
// block: the rays of a sample are then loops over plain arrays, which vectorise. The lanes
// outside the image get them too, and their rays are never traced.
struct LanePixels {
  double x[kPacketSize];
  double y[kPacketSize];
  double rotation_x[kPacketSize];
  double rotation_y[kPacketSize];
};

void find_lane_pixels(int block_x, int block_y, int samples, LanePixels& pixels) {
  for (int i = 0; i < kPacketSize; ++i) {
    const int x = block_x + i % kPacketSide;
    const int y = block_y + i / kPacketSide;
    pixels.x[i] = x;
    pixels.y[i] = y;
    const SampleRotation rotation = samples > 1 ? sample_rotation(x, y) : SampleRotation{};
    pixels.rotation_x[i] = rotation.x;
    pixels.rotation_y[i] = rotation.y;
  }
}

// Where sample `s` of each lane's pixel lies in the image: sample_offset()'s positions.
void sample_positions(const LanePixels& pixels, int samples, int s, double (&x)[kPacketSize],
                      double (&y)[kPacketSize]) {
  if (samples == 1) {
    for (int i = 0; i < kPacketSize; ++i) x[i] = pixels.x[i] + 0.5;
    for (int i = 0; i < kPacketSize; ++i) y[i] = pixels.y[i] + 0.5;
    return;
  }
  for (int i = 0; i < kPacketSize; ++i)
    x[i] = pixels.x[i] + sample_fraction(pixels.rotation_x[i], kSampleStepX, s);
  for (int i = 0; i < kPacketSize; ++i)
    y[i] = pixels.y[i] + sample_fraction(pixels.rotation_y[i], kSampleStepY, s);
}

// Row by row of the block, only its pixels inside the tile.
void store_block(const TileOutput& out, const Block& block, const double (&sums)[3][kPacketSize],
                 const SampleMean& mean) {
  for (int row = block.row_begin; row < block.row_end; ++row) {
    float* pixel = out.row_start(block, row);
    for (int column = block.column_begin; column < block.column_end; ++column, pixel += 3) {
      const int i = row * kPacketSide + column;
      const Color value = mean(Color(sums[0][i], sums[1][i], sums[2][i]));
      pixel[0] = static_cast<float>(value.r);
      pixel[1] = static_cast<float>(value.g);
      pixel[2] = static_cast<float>(value.b);
    }
  }
}

// Traces every sample of one block of the image's 4x4 grid (see render_tile()) into
// `sums`, each lane's sum of its samples by channel. `colors` is the packet's last colours:
// its lanes outside the image keep theirs from block to block, never traced. Always inlined:
// link-time optimisation then inlines the primary rays' trace_packet() into render_tile(),
// as it does with this loop written out in place, where it kept it out of line otherwise.
[[gnu::always_inline]] inline void trace_block(const Renderer& renderer, const TileRect& tile,
                                               const Block& block, Color (&colors)[kPacketSize],
                                               double (&sums)[3][kPacketSize], RayCounts& counts) {
  const Scene& scene = renderer.scene();
  const PinholeCamera& camera = renderer.camera();
  const int samples = scene.render.samples_per_pixel;
  bool in_tile[kPacketSize];
  RayPacket packet;
  for (int channel = 0; channel < 3; ++channel)
    for (int i = 0; i < kPacketSize; ++i) sums[channel][i] = 0.0;
  mark_lanes(tile, scene.width, scene.height, block.x, block.y, packet.active, in_tile);
  LanePixels pixels;
  find_lane_pixels(block.x, block.y, samples, pixels);
  const glm::vec3 eye = camera.origin();
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 0; i < kPacketSize; ++i) packet.origin[axis][i] = eye[axis];
  for (int s = 0; s < samples; ++s) {
    double x[kPacketSize];
    double y[kPacketSize];
    sample_positions(pixels, samples, s, x, y);
    camera.directions_through(x, y, packet.direction);
    renderer.tracer().trace_packet(packet, 0, in_tile, colors, counts);
    // Every lane, in tile or not: a loop without a condition stores whole vectors, which
    // the loads of store_block() can take straight from the store, where masked stores make
    // them wait.
    for (int channel = 0; channel < 3; ++channel)
      for (int i = 0; i < kPacketSize; ++i) sums[channel][i] += colors[i][channel];
  }
}

// Whether `next`, another frame of `previous`'s scene, can use the geometry built for
// `previous`: SceneGeometry reads the objects, and of their materials only whether they
// transmit light (which decides how a shape is registered).
bool same_objects(const Scene& next, const Scene& previous) {
  if (next.animation.changes_objects() || next.objects.size() != previous.objects.size())
    return false;
  for (std::size_t i = 0; i < next.objects.size(); ++i) {
    const std::uint32_t material = next.objects[i].material;
    if (material != previous.objects[i].material ||
        transmits(next.materials[material]) != transmits(previous.materials[material]))
      return false;
  }
  return true;
}

}  // namespace

Renderer::Built::Built(Scene& scene, std::shared_ptr<const Common> shared,
                       const RendererOptions& options, const SceneGeometry* previous)
    : common(std::move(shared)),
      geometry(scene, common->device, OpaquePlanes::outside_embree, options.compact_above,
               options.keep_meshes ? nullptr : &scene, previous) {}

Renderer::Renderer(Scene scene, const RendererOptions& options)
    : scene_(std::move(scene)),
      built_(
          std::make_shared<const Built>(scene_, std::make_shared<const Common>(scene_), options)),
      tracer_(scene_, built_->geometry, &built_->common->textures),
      camera_(scene_.camera, scene_.width, scene_.height) {}

Renderer::Renderer(Scene scene, const Renderer& previous, const RendererOptions& options)
    : scene_(std::move(scene)),
      built_(same_objects(scene_, previous.scene_)
                 ? previous.built_
                 : std::make_shared<const Built>(
                       scene_, previous.built_->common, options,
                       scene_.objects.size() == previous.scene_.objects.size()
                           ? &previous.built_->geometry
                           : nullptr)),
      tracer_(scene_, built_->geometry, &built_->common->textures),
      camera_(scene_.camera, scene_.width, scene_.height) {}

bool Renderer::shares_meshes_with(const Renderer& other) const {
  for (std::uint32_t i = 0; i < scene_.objects.size(); ++i) {
    const MeshBvh* mine = geometry().mesh_bvh(i);
    if (mine != nullptr && mine == other.geometry().mesh_bvh(i)) return true;
  }
  return false;
}

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
  RayCounts counts;
  const SampleMean mean(scene_.render.samples_per_pixel);
  const TileOutput output{tile, out.data(), row_stride};
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
      const Block block = block_at(tile, block_x, block_y);
      prefetch_block(output, block);
      // By channel, lanes side by side: added to channel by channel and read back as a
      // pixel's three, never loaded wider than they were stored (which would stall).
      double sums[3][kPacketSize];
      trace_block(*this, tile, block, colors, sums, counts);
      store_block(output, block, sums, mean);
    }
  }
  return counts;
}

}  // namespace tessera
