// The pinhole camera: right-handed, looking from `eye` towards `look_at`, pixel (0, 0)
// at the top left.
#pragma once

#include "common/scene.hpp"
#include "worker/ray.hpp"

namespace tessera {

class PinholeCamera {
 public:
  PinholeCamera(const Camera& camera, int width, int height);

  // The primary ray through image-plane position (x, y), measured in pixels from the
  // top-left corner of the image: the centre of pixel (i, j) is (i + 0.5, j + 0.5).
  // Inline: the renderer computes sixteen of these at a time, and they overlap.
  Ray ray_through(double x, double y) const {
    const double sx = 2.0 * x * inv_width_ - 1.0;
    const double sy = 1.0 - 2.0 * y * inv_height_;
    const Vec3 direction = glm::normalize(forward_ + sx * right_ + sy * up_);
    return Ray{glm::vec3(eye_), glm::vec3(direction)};
  }

 private:
  Vec3 eye_;
  Vec3 right_;  // scaled so that x = width maps to the right edge of the view
  Vec3 up_;     // scaled likewise for y = 0 at the top
  Vec3 forward_;
  double inv_width_;
  double inv_height_;
};

}  // namespace tessera
