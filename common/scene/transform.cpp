#include "common/scene/transform.hpp"

#include <cmath>
#include <numbers>
#include <utility>

namespace tessera {
namespace {

// Quarter turns come out exact, so axis-aligned rotations keep boxes and planes exactly
// axis-aligned instead of picking up 6e-17 terms from cos(pi/2).
std::pair<double, double> sin_cos_degrees(double degrees) {
  double reduced = std::fmod(degrees, 360.0);
  if (reduced < 0.0) reduced += 360.0;
  if (reduced == 0.0) return {0.0, 1.0};
  if (reduced == 90.0) return {1.0, 0.0};
  if (reduced == 180.0) return {0.0, -1.0};
  if (reduced == 270.0) return {-1.0, 0.0};
  const double radians = reduced * (std::numbers::pi / 180.0);
  return {std::sin(radians), std::cos(radians)};
}

Mat4 rotation_matrix(const Rotate& rotate) {
  const Vec3 k = glm::normalize(rotate.axis);
  const auto [s, c] = sin_cos_degrees(rotate.degrees);
  const double t = 1.0 - c;
  // Rodrigues: R = c I + s [k]x + (1 - c) k k^T, written out per row for GLM's m[col][row].
  Mat4 m(1.0);
  m[0][0] = c + t * k.x * k.x;
  m[1][0] = t * k.x * k.y - s * k.z;
  m[2][0] = t * k.x * k.z + s * k.y;
  m[0][1] = t * k.x * k.y + s * k.z;
  m[1][1] = c + t * k.y * k.y;
  m[2][1] = t * k.y * k.z - s * k.x;
  m[0][2] = t * k.x * k.z - s * k.y;
  m[1][2] = t * k.y * k.z + s * k.x;
  m[2][2] = c + t * k.z * k.z;
  return m;
}

struct StepMatrix {
  Mat4 operator()(const Translate& step) const {
    Mat4 m(1.0);
    m[3] = glm::dvec4(step.offset, 1.0);
    return m;
  }
  Mat4 operator()(const Rotate& step) const { return rotation_matrix(step); }
  Mat4 operator()(const Scale& step) const {
    Mat4 m(1.0);
    m[0][0] = step.factors.x;
    m[1][1] = step.factors.y;
    m[2][2] = step.factors.z;
    return m;
  }
  Mat4 operator()(const MatrixStep& step) const { return step.matrix; }
};

}  // namespace

Mat4 step_matrix(const TransformStep& step) { return std::visit(StepMatrix{}, step); }

Mat4 compose_transform(std::span<const TransformStep> steps) {
  Mat4 result(1.0);
  for (const TransformStep& step : steps) result = step_matrix(step) * result;
  return result;
}

Mat4 from_row_major(const std::array<double, 16>& rows) {
  Mat4 m(0.0);
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) m[col][row] = rows[static_cast<std::size_t>(row * 4 + col)];
  return m;
}

double linear_determinant(const Mat4& m) { return glm::determinant(glm::dmat3(m)); }

}  // namespace tessera
