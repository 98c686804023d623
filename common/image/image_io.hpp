// Image files; the format follows the file extension. PNGs are written with libpng
// (png_file.hpp); everything else, and all reading, goes through OpenImageIO, in a module
// opened on first use (image_file_module.hpp).
#pragma once

#include <cstdint>

#include <filesystem>
#include <functional>

#include "common/image/image.hpp"
#include "common/image/image_file_module.hpp"
#include "common/image/large_buffer.hpp"
#include "common/scene/scene.hpp"

namespace tessera {

// .exr: linear float, unclamped. .png, .jpg/.jpeg: 8-bit; .tif/.tiff: 16-bit; those are
// clamped to [0,1] and sRGB-encoded unless `transfer` is linear. The file appears
// atomically: it is written beside the target and renamed into place.
void write_image(const Image& image, const std::filesystem::path& path, OutputTransfer transfer,
                 ExrCompression exr_compression = ExrCompression::zip);

// The first half of write_image(): an image turned into what the file at `path` will hold
// (codes for .png, .jpg and .tif; for .exr the image's own floats, so that the image must
// outlive it). It needs none of OpenImageIO, so a program can make it while the libraries
// load (while_loading_image_files) when the format needs them. Throws std::runtime_error
// for an unknown extension.
class EncodedImage {
 public:
  EncodedImage(const Image& image, std::filesystem::path path, OutputTransfer transfer,
               ExrCompression exr_compression = ExrCompression::zip);

  const std::filesystem::path& path() const { return path_; }
  const ImageFileContent& content() const { return content_; }

 private:
  std::filesystem::path path_;
  ImageFileContent content_;
  LargeBuffer<std::uint16_t> codes16_;
  LargeBuffer<std::uint8_t> codes8_;
};

// The second half: writes `encoded` to its path, atomically as above.
void write_image(const EncodedImage& encoded);

// Reads any file OpenImageIO knows as linear float RGB (for EXR, exactly what was written).
Image read_image(const std::filesystem::path& path);

// From now on the process encodes and decodes image files on the calling thread only, for
// a process whose cores are for other work: OpenImageIO and OpenEXR start no helper
// threads of their own, and background encoding stays in the (low-priority) thread that
// asked for it.
void encode_images_on_calling_thread();

// Runs `work` on a thread of its own while the calling thread loads what reads and writes
// image files, for a program that will write one that needs it (image_file_needs_module)
// after that work (otherwise it loads when first used: 0.25 to 0.5 s here,
// docs/performance.md). Returns when both are done and rethrows what `work` threw; throws
// at once, starting nothing, if the image module is missing. Call it on the main thread:
// the libraries' constructors allocate tens of megabytes, and glibc's malloc backs only
// the main thread's heap with huge pages (huge_page_malloc.hpp), which took a quarter off
// the load.
void while_loading_image_files(const std::function<void()>& work);

// True for the extensions write_image accepts.
bool is_supported_image_path(const std::filesystem::path& path);

// True where write_image opens the image-file module (OpenImageIO) to write `path`: .exr,
// .jpg and .tif. A PNG needs none of it (png_file.hpp), so a program that will write one has
// no reason to load it (while_loading_image_files).
bool image_file_needs_module(const std::filesystem::path& path);

// Whether this process has opened the image-file module, which it never closes.
bool image_file_module_loaded();

// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0,1].
float linear_to_srgb(float linear);

// A linear value as the 8-bit sRGB code a PNG holds: by the table write_image() uses, and by
// the formula the table is built from (the test checks that they agree everywhere).
std::uint8_t srgb8_by_table(float linear);
std::uint8_t srgb8_by_formula(float linear);
// A linear value as the 8-bit code of an image written with `transfer` (what a PNG of the
// job holds).
std::uint8_t code8(float linear, OutputTransfer transfer);

}  // namespace tessera
