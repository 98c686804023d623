// PNG files written with libpng itself rather than through OpenImageIO
// (image_file_module.hpp): PNG is what `tessera render` writes by default and what the
// coordinator serves unless asked for another format, and opening OpenImageIO's ~260
// libraries for it took half the wall time of a 1080p render (docs/performance.md, "PNG
// with libpng"). libpng and zlib are two small libraries, loaded at start.
#pragma once

#include <cstdint>
#include <filesystem>

namespace tessera {

// How the pixel rows are compressed. The defaults are what write_image() uses: zlib level 2
// with every row filtered by "sub" (docs/performance.md, "PNG with libpng", has the figures
// for the other choices on 1920x1080 renders).
struct PngCompression {
  enum class Filter { none, sub, adaptive };  // adaptive: libpng's choice per row, by trial
  int zlib_level = 2;
  Filter filter = Filter::sub;
};

// 8-bit RGB, width × height × 3 codes, rows top to bottom, already quantised by the caller
// (image_io.cpp), so that the bytes never depend on libpng. `srgb` labels them: an sRGB
// chunk (with the gAMA and cHRM chunks it implies for older readers) when true, gAMA 1.0
// (linear) when false.
struct PngPixels {
  int width = 0;
  int height = 0;
  const std::uint8_t* rgb = nullptr;
  bool srgb = true;
};

// Writes a new file at `path`, replacing any. Throws std::runtime_error saying what failed
// without naming the file: the caller, write_image(), writes to a temporary file and names
// the one it was asked for. May leave a partial file, which the caller removes.
void write_png(const std::filesystem::path& path, const PngPixels& pixels,
               const PngCompression& compression = {});

}  // namespace tessera
