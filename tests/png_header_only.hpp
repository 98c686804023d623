// Hostile images for the tests of texture limits (tests/unit/worker/texture_test.cpp,
// tests/farm/farm_assets_test.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace tessera::test {

// A PNG whose header claims `width` x `height` 8-bit RGB pixels, with none behind it (an
// empty IDAT): only a reader that believes the header before it spends anything would be
// hurt by it.
inline std::string png_header_only(std::uint32_t width, std::uint32_t height) {
  const auto crc32 = [](std::string_view bytes) {
    std::uint32_t crc = 0xffffffffu;
    for (const char c : bytes) {
      crc ^= static_cast<unsigned char>(c);
      for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
  };
  const auto big_endian = [](std::uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16),
                       static_cast<char>(v >> 8), static_cast<char>(v)};
  };
  const auto chunk = [&](const std::string& type, const std::string& data) {
    return big_endian(static_cast<std::uint32_t>(data.size())) + type + data +
           big_endian(crc32(type + data));
  };
  const std::string ihdr =
      big_endian(width) + big_endian(height) + std::string("\x08\x02\0\0\0", 5);
  return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", "") +
         chunk("IEND", "");
}

}  // namespace tessera::test
