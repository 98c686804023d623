// The boundary between image_io.cpp and the module that holds OpenImageIO
// (image_file_module.cpp, built as lib/tessera/libtessera_image_files.so).
//
// Why a module: Debian's OpenImageIO brings about 260 shared libraries, and loading them
// takes about 0.13 s at every start of every program linked against it, including each
// `tessera status` that never touches an image. Opened with dlopen() when an image is first
// read, or written in a format other than PNG (or earlier, while other work runs, by a
// program that knows it will write one), they cost only the programs that use them. Both
// sides are built from this tree by one compiler, so C++ types cross the boundary
// unchanged; errors cross as exceptions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/protocol/image_format.hpp"
#include "common/scene/scene.hpp"

namespace tessera {

// What one written file holds: width × height × 3 channels, rows top to bottom. `pixels`
// points at float for exr, std::uint16_t for tif and std::uint8_t otherwise, already
// quantised and encoded by the caller; `srgb` only labels the file.
// How an EXR is compressed, both lossless: ZIP makes the smaller file; RLE costs about a
// sixth of ZIP's time for a half more bytes on rendered floats (a 640x360 frame here: 10.5
// against 61 ms, 2.65 against 1.76 MB; docs/performance.md), for files written on
// machines whose cores render.
enum class ExrCompression { zip, rle };

struct ImageFileContent {
  ImageFileKind kind = ImageFileKind::unknown;
  int width = 0;
  int height = 0;
  bool srgb = false;
  const void* pixels = nullptr;
  ExrCompression exr_compression = ExrCompression::zip;
};

// Where a texture is looked up: s across the image from its left edge, t down from its top,
// both 0 to 1 over the image, and how far each moves from one edge of the ray's footprint
// to the other (its two axes, x and y).
struct TextureFootprint {
  float s, t;
  float dsdx, dtdx;
  float dsdy, dtdy;
};

// A scene's textures, decoded, in linear RGB and mip-mapped, ready for filtered lookups from
// any thread (OpenImageIO's TextureSystem, texture_files.cpp).
class TextureSampler {
 public:
  virtual ~TextureSampler() = default;
  // Texture `index`'s colour, filtered over the footprint: bilinear within a mip level, the
  // levels (and the anisotropic probes along the footprint's long axis) chosen by its size.
  // The result depends only on the arguments.
  virtual void sample(std::size_t index, TextureWrap wrap, const TextureFootprint& at,
                      float (&rgb)[3]) const = 0;
};

// The most pixels a texture may have: 8192 x 8192; and all of a scene's textures together:
// four times that. A decoded mip-map takes about 16 bytes a pixel, so no scene can make a
// worker spend more than about 4 GiB on its textures.
inline constexpr std::uint64_t kMaxTexturePixels = std::uint64_t{8192} * 8192;
inline constexpr std::uint64_t kMaxSceneTexturePixels = 4 * kMaxTexturePixels;

// Why a scene whose distinct textures have `pixels` together, over kMaxSceneTexturePixels,
// is refused.
inline std::string too_many_texture_pixels(std::uint64_t pixels) {
  return "the scene's textures have " + std::to_string(pixels) +
         " pixels together, more than the " + std::to_string(kMaxSceneTexturePixels) +
         " a scene's may have";
}

struct ImageFileModule {
  // Writes `content` to `path` (whose extension names the format): EXR, TIFF and JPEG, PNGs
  // being written without the module (png_file.hpp). Throws std::runtime_error saying what
  // failed; may leave a partial file, which the caller removes.
  void (*write)(const std::string& path, const ImageFileContent& content);
  // Reads any file OpenImageIO knows as float RGB; a channel the file lacks repeats its
  // last one (grey for one channel). Throws std::runtime_error saying what failed.
  std::vector<float> (*read)(const std::string& path, int& width, int& height);
  // OpenImageIO and OpenEXR start no threads of their own from now on.
  void (*encode_on_calling_thread)();
  // Decodes each image (8- and 16-bit images from sRGB, unless the file says it is linear)
  // and builds its mip-map, after check_textures(): nothing is decoded for images over a
  // limit. Throws std::runtime_error naming the image that fails.
  std::unique_ptr<TextureSampler> (*open_textures)(const std::vector<TextureImage>& images);
  // Reads the images' headers only (a scene's, each once: texture_images.hpp): throws
  // std::runtime_error naming an image that is not one open_textures() can read, or has
  // more than kMaxTexturePixels, or saying the images together have more than
  // kMaxSceneTexturePixels.
  void (*check_textures)(const std::vector<TextureImage>& images);
};

}  // namespace tessera

// The module's one exported symbol: dlsym() finds it by this unmangled name.
extern "C" const tessera::ImageFileModule* tessera_image_file_module();
