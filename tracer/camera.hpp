// The pinhole camera: right-handed, looking from `eye` towards `look_at`, pixel (0, 0)
// at the top left.
#pragma once

#include "common/scene/scene.hpp"
#include "tracer/ray.hpp"
#include "tracer/tracer_api.hpp"

namespace tessera {

class PinholeCamera {
 public:
  PinholeCamera(const Camera& camera, int width, int height);

  // The primary ray through image-plane position (x, y), measured in pixels from the
  // top-left corner of the image: the centre of pixel (i, j) is (i + 0.5, j + 0.5).
  // One ray at a time; packets take directions_through().
  Ray ray_through(double x, double y) const {
    const double sx = 2.0 * x * inv_width_ - 1.0;
    const double sy = 1.0 - 2.0 * y * inv_height_;
    const Vec3 direction = glm::normalize(forward_ + sx * right_ + sy * up_);
    return Ray{glm::vec3(eye_), glm::vec3(direction)};
  }

  // Where every primary ray starts.
  glm::vec3 origin() const { return glm::vec3(eye_); }

  // The directions of ray_through() for a packet's sixteen positions: lane by lane the
  // same operations in the same order, so each has ray_through()'s bits, but in loops over
  // plain arrays that vectorise. Lane by lane, each ray's square root and division waited
  // on the previous lane's (docs/performance.md). Out of line, in the tracer's library, so
  // that the benchmark's bare Embree loop runs the very same instructions.
  TESSERA_TRACER_API void directions_through(const double (&x)[kPacketSize],
                                             const double (&y)[kPacketSize],
                                             float (&direction)[3][kPacketSize]) const;

 private:
  Vec3 eye_;
  Vec3 right_;  // scaled so that x = width maps to the right edge of the view
  Vec3 up_;     // scaled likewise for y = 0 at the top
  Vec3 forward_;
  double inv_width_;
  double inv_height_;
};

}  // namespace tessera
