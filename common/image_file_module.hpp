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

#include <cstdint>
#include <string>
#include <vector>

#include "common/image_format.hpp"

namespace tessera {

// What one written file holds: width × height × 3 channels, rows top to bottom. `pixels`
// points at float for exr, std::uint16_t for tif and std::uint8_t otherwise, already
// quantised and encoded by the caller; `srgb` only labels the file.
struct ImageFileContent {
  ImageFileKind kind = ImageFileKind::unknown;
  int width = 0;
  int height = 0;
  bool srgb = false;
  const void* pixels = nullptr;
};

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
};

}  // namespace tessera

// The module's one exported symbol: dlsym() finds it by this unmangled name.
extern "C" const tessera::ImageFileModule* tessera_image_file_module();
