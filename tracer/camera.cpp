#include "tracer/camera.hpp"

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

void PinholeCamera::directions_through(const double (&x)[kPacketSize],
                                       const double (&y)[kPacketSize],
                                       float (&direction)[3][kPacketSize]) const {
  // Plain locals: GCC keeps them in registers across the loop's stores.
  const double fx = forward_.x, fy = forward_.y, fz = forward_.z;
  const double rx = right_.x, ry = right_.y, rz = right_.z;
  const double ux = up_.x, uy = up_.y, uz = up_.z;
  const double inv_width = inv_width_, inv_height = inv_height_;
  // forward_ + sx * right_ + sy * up_, lane by lane.
  double v[3][kPacketSize];
  for (int i = 0; i < kPacketSize; ++i) {
    const double sx = 2.0 * x[i] * inv_width - 1.0;
    const double sy = 1.0 - 2.0 * y[i] * inv_height;
    v[0][i] = fx + sx * rx + sy * ux;
    v[1][i] = fy + sx * ry + sy * uy;
    v[2][i] = fz + sx * rz + sy * uz;
  }
  normalize_lanes(v, direction);
}

}  // namespace tessera
