// Rays as Embree sees them: single precision. Geometry recomputes hits in double from
// exactly these floats, so a hit never depends on which ISA path Embree took.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

#include "common/scene/scene.hpp"

namespace tessera {

// No default values: packets hold sixteen of these, filled only where a lane is active, and
// zeroing them first costs more than tracing a ray.
struct Ray {
  glm::vec3 origin;
  glm::vec3 direction;  // unit
};

// Primary rays go to Embree sixteen at a time, as a 4x4 block of pixels.
inline constexpr int kPacketSide = 4;
inline constexpr int kPacketSize = kPacketSide * kPacketSide;

inline constexpr float kInfinity = std::numeric_limits<float>::infinity();

// glm::vec3(glm::normalize(v)) for sixteen vectors at once: lane by lane glm's operations
// in glm's order, v · (1 / sqrt(v · v)) with the sum (x + y) + z, so each lane has the bits
// of a single vector's; but in a loop over plain arrays, which vectorises, where lane by
// lane each square root and division waited on the previous lane's.
inline void normalize_lanes(const double (&v)[3][kPacketSize], float (&unit)[3][kPacketSize]) {
  for (int i = 0; i < kPacketSize; ++i) {
    const double inverse_length =
        1.0 / std::sqrt(v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i]);
    for (int axis = 0; axis < 3; ++axis)
      unit[axis][i] = static_cast<float>(v[axis][i] * inverse_length);
  }
}

// Moves a surface point off the surface, to the side `towards` points to, by an amount
// that grows with the magnitude of its coordinates: a few hundred units in the last place
// away from the origin, a fixed small distance near it. This follows the method of Wächter
// and Binder (Ray Tracing Gems, ch. 6) and keeps secondary rays free of self-intersection
// on large and far-away surfaces, where a fixed epsilon fails.
//
// `side` is +1 to move along the normal, -1 against it.
inline glm::vec3 offset_ray_origin(const Vec3& point, const Vec3& normal, float side) {
  constexpr float kOriginZone = 1.0f / 32.0f;
  constexpr float kFloatScale = 1.0f / 65536.0f;
  constexpr float kIntScale = 256.0f;
  // Both offsets are worked out and one is selected, without branches: which one a
  // coordinate takes varies from ray to ray and would be mispredicted.
  glm::vec3 out;
  for (int i = 0; i < 3; ++i) {
    const float p = static_cast<float>(point[i]);
    const float nf = side * static_cast<float>(normal[i]);
    const float near = p + kFloatScale * nf;
    const auto ulps = static_cast<std::int32_t>(kIntScale * nf);
    const auto bits = std::bit_cast<std::int32_t>(p);
    const float far = std::bit_cast<float>(bits + (p < 0.0f ? -ulps : ulps));
    out[i] = std::fabs(p) < kOriginZone ? near : far;
  }
  return out;
}

// The side of the surface `towards` points to, as offset_ray_origin() takes it.
inline float side_towards(const Vec3& normal, const Vec3& towards) {
  return glm::dot(normal, towards) < 0.0 ? -1.0f : 1.0f;
}

// The origin moved off the surface to the side `towards` points to.
inline glm::vec3 offset_ray_origin(const Vec3& point, const Vec3& normal, const Vec3& towards) {
  return offset_ray_origin(point, normal, side_towards(normal, towards));
}

}  // namespace tessera
