#include "common/image/png_file.hpp"

#include <png.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>

namespace tessera {
namespace {

// What went wrong, recorded by the callbacks before they jump back to encode().
struct Failure {
  char message[256] = "";
  int error_number = 0;  // errno of a failed write; 0 for libpng's own errors
};

std::string describe(int error_number) {
  return std::error_code(error_number, std::generic_category()).message();
}

// libpng's error callback must not return. An exception thrown from here would unwind
// through libpng's C frames, which need not support it, so it jumps back to encode().
[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  auto* failure = static_cast<Failure*>(png_get_error_ptr(png));
  std::snprintf(failure->message, sizeof failure->message, "%s", message);
  png_longjmp(png, 1);
}

// A library has no business printing on its callers' stderr.
void on_warning(png_structp, png_const_charp) {}

// Our own writer rather than png_init_io()'s, which reports a failed write only as "Write
// Error": this keeps its errno (a full disk, a file size limit) for the message.
void write_data(png_structp png, png_bytep data, std::size_t length) {
  if (std::fwrite(data, 1, length, static_cast<std::FILE*>(png_get_io_ptr(png))) != length) {
    static_cast<Failure*>(png_get_error_ptr(png))->error_number = errno;
    png_error(png, "write failed");
  }
}

// Nothing to do before the end, where write_png() checks what fclose() says.
void flush_data(png_structp) {}

int filter_mask(PngCompression::Filter filter) {
  switch (filter) {
    case PngCompression::Filter::none:
      return PNG_FILTER_NONE;
    case PngCompression::Filter::sub:
      return PNG_FILTER_SUB;
    case PngCompression::Filter::adaptive:
      return PNG_ALL_FILTERS;
  }
  return PNG_FILTER_SUB;
}

// The write struct and its info struct, destroyed together however write_png() ends.
class PngWriteStruct {
 public:
  explicit PngWriteStruct(Failure& failure)
      : png_(png_create_write_struct(PNG_LIBPNG_VER_STRING, &failure, on_error, on_warning)) {
    if (png_ == nullptr) throw std::runtime_error("libpng failed to start (out of memory?)");
    info_ = png_create_info_struct(png_);
    if (info_ == nullptr) {
      png_destroy_write_struct(&png_, nullptr);
      throw std::runtime_error("libpng failed to start (out of memory?)");
    }
  }
  ~PngWriteStruct() { png_destroy_write_struct(&png_, &info_); }
  PngWriteStruct(const PngWriteStruct&) = delete;
  PngWriteStruct& operator=(const PngWriteStruct&) = delete;

  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  png_structp png_;
  png_infop info_ = nullptr;
};

struct CloseFile {
  void operator()(std::FILE* file) const { std::fclose(file); }
};

// Every libpng call that can fail is made here, below the setjmp() its errors jump back to.
// longjmp() skips destructors, so this frame holds nothing that has one; and nothing changed
// after setjmp() is read after the jump, so no local needs to be volatile.
bool encode(png_structp png, png_infop info, std::FILE* file, const PngPixels& pixels,
            const PngCompression& compression) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_write_fn(png, file, write_data, flush_data);
  png_set_IHDR(png, info, static_cast<png_uint_32>(pixels.width),
               static_cast<png_uint_32>(pixels.height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // Viewers that manage colour read the sRGB chunk; older ones the gAMA and cHRM that go with
  // it. Linear codes say so with a gamma of 1, so that no viewer takes them for sRGB.
  if (pixels.srgb)
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  else
    png_set_gAMA_fixed(png, info, PNG_FP_1);
  png_set_compression_level(png, compression.zlib_level);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, filter_mask(compression.filter));
  png_write_info(png, info);
  const std::size_t row_bytes = static_cast<std::size_t>(pixels.width) * 3;
  for (int y = 0; y < pixels.height; ++y)
    png_write_row(png, pixels.rgb + static_cast<std::size_t>(y) * row_bytes);
  png_write_end(png, nullptr);
  return true;
}

}  // namespace

void write_png(const std::filesystem::path& path, const PngPixels& pixels,
               const PngCompression& compression) {
  Failure failure;
  const PngWriteStruct writer(failure);
  std::unique_ptr<std::FILE, CloseFile> file(std::fopen(path.c_str(), "wb"));
  if (!file) throw std::runtime_error(describe(errno));
  if (!encode(writer.png(), writer.info(), file.get(), pixels, compression))
    throw std::runtime_error(failure.error_number != 0 ? describe(failure.error_number)
                                                       : std::string("libpng: ") + failure.message);
  // The last buffered bytes reach the file only now, so a full disk may show only here.
  if (std::fclose(file.release()) != 0) throw std::runtime_error(describe(errno));
}

}  // namespace tessera
