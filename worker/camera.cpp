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

}  // namespace tessera
