// Object-to-world matrices from the transform steps of a scene file.
#pragma once

#include <array>
#include <span>
#include <variant>

#include "common/scene/scene.hpp"

namespace tessera {

struct Translate {
  Vec3 offset{0.0};
};

// Right-hand rule: positive degrees turn counter-clockwise seen from the axis tip.
struct Rotate {
  Vec3 axis{0.0, 1.0, 0.0};  // non-zero; need not be unit
  double degrees = 0.0;
};

struct Scale {
  Vec3 factors{1.0};  // no zero component
};

struct MatrixStep {
  Mat4 matrix{1.0};  // affine
};

using TransformStep = std::variant<Translate, Rotate, Scale, MatrixStep>;

Mat4 step_matrix(const TransformStep& step);

// steps[0] is applied to the object first, so the result is steps[n-1] * ... * steps[0].
Mat4 compose_transform(std::span<const TransformStep> steps);

// Scene files write matrices row by row; GLM stores them column by column.
Mat4 from_row_major(const std::array<double, 16>& rows);

// Determinant of the upper-left 3x3 block: zero when the transform flattens space.
double linear_determinant(const Mat4& m);

}  // namespace tessera
