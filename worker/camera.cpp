#include "worker/camera.hpp"

#include <cmath>

namespace tessera {

PinholeCamera::PinholeCamera(const Camera& camera, int width, int height)
    : eye_(camera.eye), inv_width_(1.0 / width), inv_height_(1.0 / height) {
  const Vec3 w = glm::normalize(camera.eye - camera.look_at);  // the camera looks along -w
  const Vec3 u = glm::normalize(glm::cross(camera.up, w));
  const Vec3 v = glm::cross(w, u);
  const double half_height = std::tan(glm::radians(camera.fov_y_degrees) / 2.0);
  const double half_width = half_height * width / height;
  forward_ = -w;
  right_ = half_width * u;
  up_ = half_height * v;
}

Ray PinholeCamera::ray_through(double x, double y) const {
  const double sx = 2.0 * x * inv_width_ - 1.0;
  const double sy = 1.0 - 2.0 * y * inv_height_;
  const Vec3 direction = glm::normalize(forward_ + sx * right_ + sy * up_);
  return Ray{glm::vec3(eye_), glm::vec3(direction)};
}

}  // namespace tessera
