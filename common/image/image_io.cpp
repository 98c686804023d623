#include "common/image/image_io.hpp"

#include <unistd.h>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/image/image_file_loader.hpp"
#include "common/image/png_file.hpp"

namespace tessera {
namespace {

ImageFileKind kind_of(const std::filesystem::path& path) {
  const ImageFormat* format = image_format_of_path(path);
  return format ? format->kind : ImageFileKind::unknown;
}

// Quantises in our own code, not OIIO's, so that the bytes never depend on its version.
template <typename T>
T quantise(float v, OutputTransfer transfer) {
  constexpr float max_code = static_cast<float>(std::numeric_limits<T>::max());
  float c = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);
  if (transfer == OutputTransfer::srgb) c = linear_to_srgb(c);
  return static_cast<T>(std::lround(c * max_code));
}

// 8-bit sRGB by table: thresholds_[k] is the least value in [0, 1] that quantise() takes to
// code k + 1 or above, found by bisection over the floats themselves, so the table gives
// quantise()'s own answer without a pow() per channel. A binary search through the
// thresholds mispredicts a branch at nearly every step, so the lookup goes through buckets
// instead: the top 16 bits of a float in [0, 1) pick one of 16,256 buckets, each holding
// the code of its least value, and one comparison with the next threshold finishes it. A
// bucket is at most 0.65 as wide as the gap between two thresholds near it (the gaps grow
// as v^0.58, the buckets as v, and the ratio peaks just above 0.5), so it never holds two
// of them; the constructor checks that.
class Srgb8Table {
 public:
  Srgb8Table() {
    for (int k = 0; k < 255; ++k) {
      std::uint32_t lo = std::bit_cast<std::uint32_t>(0.0f);  // code <= k
      std::uint32_t hi = kOneBits;                            // code >= k + 1
      while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        (code(mid) > k ? hi : lo) = mid;
      }
      thresholds_[k] = std::bit_cast<float>(hi);
    }
    thresholds_[255] = std::numeric_limits<float>::infinity();  // no code above 255
    for (std::uint32_t bucket = 0; bucket < kBuckets; ++bucket) {
      const float least = std::bit_cast<float>(bucket << kBucketShift);
      const float most = std::bit_cast<float>(((bucket + 1) << kBucketShift) - 1);
      const auto start = std::upper_bound(thresholds_, thresholds_ + 255, least) - thresholds_;
      if (start < 255 && most >= thresholds_[start + 1])
        throw std::logic_error("sRGB table: a bucket holds two code steps");
      start_[bucket] = static_cast<std::uint8_t>(start);
    }
  }
  std::uint8_t operator()(float v) const {
    const auto bits = std::bit_cast<std::uint32_t>(v);
    if (bits < kOneBits) {  // [0, 1)
      const std::uint8_t start = start_[bits >> kBucketShift];
      return static_cast<std::uint8_t>(start + (v >= thresholds_[start]));
    }
    // 1 and above, infinity included, are 255; NaN and negative values (sign bit set) are 0.
    return bits <= std::bit_cast<std::uint32_t>(std::numeric_limits<float>::infinity()) ? 255 : 0;
  }

 private:
  static constexpr std::uint32_t kOneBits = std::bit_cast<std::uint32_t>(1.0f);
  static constexpr unsigned kBucketShift = 16;
  static constexpr std::uint32_t kBuckets = kOneBits >> kBucketShift;
  static int code(std::uint32_t bits) {
    return quantise<std::uint8_t>(std::bit_cast<float>(bits), OutputTransfer::srgb);
  }
  float thresholds_[256];
  std::uint8_t start_[kBuckets];
};

// Every element of the result is written, so it is not zeroed first.
template <typename T>
LargeBuffer<T> encode(const Image& image, OutputTransfer transfer) {
  LargeBuffer<T> out(image.pixels().size());
  if constexpr (std::is_same_v<T, std::uint8_t>) {
    if (transfer == OutputTransfer::srgb) {
      static const Srgb8Table table;
      std::transform(image.pixels().begin(), image.pixels().end(), out.begin(), table);
      return out;
    }
  }
  std::transform(image.pixels().begin(), image.pixels().end(), out.begin(),
                 [&](float v) { return quantise<T>(v, transfer); });
  return out;
}

}  // namespace

std::uint8_t srgb8_by_table(float linear) {
  static const Srgb8Table table;
  return table(linear);
}

std::uint8_t code8(float linear, OutputTransfer transfer) {
  if (transfer == OutputTransfer::srgb) return srgb8_by_table(linear);
  return quantise<std::uint8_t>(linear, transfer);
}

std::uint8_t srgb8_by_formula(float linear) {
  return quantise<std::uint8_t>(linear, OutputTransfer::srgb);
}

float linear_to_srgb(float linear) {
  if (linear <= 0.0031308f) return 12.92f * linear;
  return 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

void encode_images_on_calling_thread() { image_files().encode_on_calling_thread(); }

void while_loading_image_files(const std::function<void()>& work) {
  ImageFileLoader::instance().open_during(work);
}

bool is_supported_image_path(const std::filesystem::path& path) {
  return kind_of(path) != ImageFileKind::unknown;
}

bool image_file_needs_module(const std::filesystem::path& path) {
  const ImageFileKind kind = kind_of(path);
  return kind != ImageFileKind::png && kind != ImageFileKind::unknown;
}

bool image_file_module_loaded() { return ImageFileLoader::instance().opened(); }

EncodedImage::EncodedImage(const Image& image, std::filesystem::path path, OutputTransfer transfer,
                           ExrCompression exr_compression)
    : path_(std::move(path)) {
  const ImageFileKind kind = kind_of(path_);
  if (kind == ImageFileKind::unknown)
    throw std::runtime_error("cannot write " + path_.string() + ": unknown image extension (use " +
                             image_format_names(true) + ")");
  content_.kind = kind;
  content_.width = image.width();
  content_.height = image.height();
  content_.srgb = kind != ImageFileKind::exr && transfer == OutputTransfer::srgb;
  content_.exr_compression = exr_compression;
  if (kind == ImageFileKind::exr) {
    content_.pixels = image.pixels().data();
  } else if (kind == ImageFileKind::tif) {
    codes16_ = encode<std::uint16_t>(image, transfer);
    content_.pixels = codes16_.data();
  } else {
    codes8_ = encode<std::uint8_t>(image, transfer);
    content_.pixels = codes8_.data();
  }
}

void write_image(const EncodedImage& encoded) {
  const std::filesystem::path& path = encoded.path();
  const ImageFileContent& content = encoded.content();
  // Same directory and extension, so the rename is atomic and OIIO picks the right format.
  std::filesystem::path temp = path;
  temp.replace_filename("." + path.stem().string() + ".tmp" + std::to_string(::getpid()) +
                        path.extension().string());
  try {
    if (content.kind == ImageFileKind::png)
      write_png(temp, PngPixels{content.width, content.height,
                                static_cast<const std::uint8_t*>(content.pixels), content.srgb});
    else
      image_files().write(temp.string(), content);
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw std::runtime_error("cannot write " + path.string() + ": " + e.what());
  }
  std::filesystem::rename(temp, path);
}

void write_image(const Image& image, const std::filesystem::path& path, OutputTransfer transfer,
                 ExrCompression exr_compression) {
  write_image(EncodedImage(image, path, transfer, exr_compression));
}

Image read_image(const std::filesystem::path& path) {
  int width = 0, height = 0;
  std::vector<float> rgb;
  try {
    rgb = image_files().read(path.string(), width, height);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot read " + path.string() + ": " + e.what());
  }
  Image image(width, height);
  std::copy(rgb.begin(), rgb.end(), image.pixels().begin());
  return image;
}

}  // namespace tessera
