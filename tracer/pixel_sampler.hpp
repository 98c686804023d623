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

// The rotation of a pixel's sequence: two fractions from a hash of its coordinates.
struct SampleRotation {
  double x;
  double y;
};

inline SampleRotation sample_rotation(int pixel_x, int pixel_y) {
  const std::uint64_t h =
      mix_bits((static_cast<std::uint64_t>(static_cast<std::uint32_t>(pixel_x)) << 32) |
               static_cast<std::uint32_t>(pixel_y));
  return {static_cast<double>(h >> 40) * 0x1p-24,
          static_cast<double>((h >> 16) & 0xffffff) * 0x1p-24};
}

// 1/φ₂ and 1/φ₂², φ₂ being the plastic number, the 2D analogue of the golden ratio: the
// sequence's steps along x and y.
inline constexpr double kSampleStepX = 0.7548776662466927;
inline constexpr double kSampleStepY = 0.5698402909980532;

// Sample `index`'s place across the pixel along one axis, from that axis's rotation and
// step, in [0, 1).
inline double sample_fraction(double rotation, double step, int index) {
  const double v = rotation + step * index;
  return v - std::floor(v);
}

inline SampleOffset sample_offset(int pixel_x, int pixel_y, int index, int count) {
  if (count == 1) return {0.5, 0.5};
  const SampleRotation rotation = sample_rotation(pixel_x, pixel_y);
  return {sample_fraction(rotation.x, kSampleStepX, index),
          sample_fraction(rotation.y, kSampleStepY, index)};
}

}  // namespace tessera
