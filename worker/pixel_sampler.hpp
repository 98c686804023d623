// Where inside a pixel its samples fall. One sample: the centre. More: Roberts' R2
// low-discrepancy sequence, rotated per pixel by a hash of the pixel's coordinates
// (Cranley–Patterson), so that a pixel's samples depend on nothing but the pixel.
#pragma once

#include <cmath>
#include <cstdint>

namespace tessera {

struct SampleOffset {
  double x;
  double y;
};

// A 64-bit finaliser (the SplitMix64 mixing steps): adjacent inputs give unrelated outputs.
inline std::uint64_t mix_bits(std::uint64_t v) {
  v ^= v >> 30;
  v *= 0xbf58476d1ce4e5b9ull;
  v ^= v >> 27;
  v *= 0x94d049bb133111ebull;
  v ^= v >> 31;
  return v;
}

inline SampleOffset sample_offset(int pixel_x, int pixel_y, int index, int count) {
  if (count == 1) return {0.5, 0.5};
  // 1/φ₂ and 1/φ₂², φ₂ being the plastic number, the 2D analogue of the golden ratio.
  constexpr double kA1 = 0.7548776662466927;
  constexpr double kA2 = 0.5698402909980532;
  const std::uint64_t h =
      mix_bits((static_cast<std::uint64_t>(static_cast<std::uint32_t>(pixel_x)) << 32) |
               static_cast<std::uint32_t>(pixel_y));
  const double rx = static_cast<double>(h >> 40) * 0x1p-24;
  const double ry = static_cast<double>((h >> 16) & 0xffffff) * 0x1p-24;
  double x = rx + kA1 * index;
  double y = ry + kA2 * index;
  return {x - std::floor(x), y - std::floor(y)};
}

}  // namespace tessera
