// Image files through OpenImageIO (loaded on first use: image_file_module.hpp); the format
// follows the file extension.
#pragma once

#include <cstdint>

#include <filesystem>

#include "common/image.hpp"
#include "common/scene.hpp"

namespace tessera {

// .exr: linear float, unclamped. .png, .jpg/.jpeg: 8-bit; .tif/.tiff: 16-bit; those are
// clamped to [0,1] and sRGB-encoded unless `transfer` is linear. The file appears
// atomically: it is written beside the target and renamed into place.
void write_image(const Image& image, const std::filesystem::path& path, OutputTransfer transfer);

// Reads any file OpenImageIO knows as linear float RGB (for EXR, exactly what was written).
Image read_image(const std::filesystem::path& path);

// From now on the process encodes and decodes image files on the calling thread only, for
// a process whose cores are for other work: OpenImageIO and OpenEXR start no helper
// threads of their own, and background encoding stays in the (low-priority) thread that
// asked for it.
void encode_images_on_calling_thread();

// Starts loading what reads and writes image files on a thread of its own, for a program
// that will write one after other work: otherwise it loads when first used (about 0.1 s;
// docs/performance.md).
void start_loading_image_files();

// True for the extensions write_image accepts.
bool is_supported_image_path(const std::filesystem::path& path);

// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0,1].
float linear_to_srgb(float linear);

// A linear value as the 8-bit sRGB code a PNG holds: by the table write_image() uses, and by
// the formula the table is built from (the test checks that they agree everywhere).
std::uint8_t srgb8_by_table(float linear);
std::uint8_t srgb8_by_formula(float linear);

}  // namespace tessera
