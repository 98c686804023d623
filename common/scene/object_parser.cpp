#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>
#include <vector>

#include "common/scene/scene_parser_parts.hpp"
#include "common/scene/scene_stream.hpp"
#include "common/scene/transform.hpp"

namespace tessera {
namespace {

// Below this a transform squashes objects so flat that inverting it (to bring rays into
// object space) loses all precision.
constexpr double min_determinant = 1e-12;

constexpr std::string_view step_kinds[] = {"translate", "rotate", "scale", "matrix"};

double nonzero_number(const ValueReader& value) {
  const double v = value.number();
  if (v == 0.0) value.fail("must be non-zero, got 0");
  return v;
}

Rotate parse_rotate(const ValueReader& value) {
  const ObjectReader reader(value, "an object {\"axis\": [x, y, z], \"degrees\": angle}");
  reader.allow_only({"axis", "degrees"});
  return Rotate{
      reader.require("axis").animated([](const ValueReader& v) { return v.direction(); }),
      reader.require("degrees").animated([](const ValueReader& v) { return v.number(); })};
}

Scale parse_scale(const ValueReader& value) {
  if (value.json().is_number()) return Scale{Vec3(nonzero_number(value))};
  value.expect_array_of(3, "a number or an array of 3 numbers");
  return Scale{Vec3(nonzero_number(value.element(0)), nonzero_number(value.element(1)),
                    nonzero_number(value.element(2)))};
}

MatrixStep parse_matrix(const ValueReader& value) {
  value.expect_array_of(16, "an array of 16 numbers (row-major 4x4 matrix)");
  std::array<double, 16> rows{};
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = value.element(i).number();
  if (rows[12] != 0.0 || rows[13] != 0.0 || rows[14] != 0.0 || rows[15] != 1.0) {
    value.fail("must be affine: its last row must be [0, 0, 0, 1], got [" +
               format_number(rows[12]) + ", " + format_number(rows[13]) + ", " +
               format_number(rows[14]) + ", " + format_number(rows[15]) + "]");
  }
  const Mat4 matrix = from_row_major(rows);
  const double det = linear_determinant(matrix);
  if (!(std::abs(det) >= min_determinant))
    value.fail("must be invertible, but its 3x3 part has determinant " + format_number(det));
  return MatrixStep{matrix};
}

TransformStep parse_step(const ValueReader& value) {
  const ObjectReader reader(value, "a transform step object");
  reader.allow_only(step_kinds);
  if (reader.members().size() != 1) {
    value.fail("must have exactly one of " + quoted_list(step_kinds) + ", got " +
               std::to_string(reader.members().size()) + " keys");
  }
  const std::string& kind = reader.members().begin()->first;
  const ValueReader argument = reader.require(kind);
  if (kind == "translate")
    return Translate{argument.animated([](const ValueReader& v) { return v.vec3(); })};
  if (kind == "rotate") return parse_rotate(argument);
  if (kind == "scale") return argument.animated(parse_scale);
  return parse_matrix(argument);
}

const ShapeType& find_shape_type(const ObjectReader& reader) {
  const auto types = shape_types();
  std::vector<std::string_view> names;
  for (const ShapeType& type : types) names.push_back(type.name);
  const std::string_view name = reader.require("type").choice(names);
  return *std::find_if(types.begin(), types.end(),
                       [&](const ShapeType& type) { return type.name == name; });
}

// Appends what one element of "objects" is to `out`: one Object, or one per part of a mesh
// file. `triangles` is the sum over the objects before it.
void parse_object(const ValueReader& value, MaterialTable& materials, const ObjectContext& context,
                  std::size_t triangles, std::vector<Object>& out) {
  const ObjectReader reader(value, "an object (scene object)");
  if (is_mesh_file(reader)) {
    parse_mesh_file(reader, materials, context, triangles, out);
    return;
  }
  const ShapeType& type = find_shape_type(reader);
  std::vector<std::string_view> keys = {"type", "material", "transform"};
  keys.insert(keys.end(), type.keys.begin(), type.keys.end());
  reader.allow_only(keys);

  Object object;
  object.shape = type.parse(reader);
  if (const auto material = reader.find("material")) object.material = materials.resolve(*material);
  if (const auto transform = reader.find("transform"))
    object.transform = parse_transform(*transform);
  out.push_back(std::move(object));
}

void check_object_count(const ValueReader& objects, std::size_t count, const Limits& limits) {
  if (count > limits.max_objects) {
    objects.fail_limit("must have <= " + std::to_string(limits.max_objects) +
                           " elements (limit max_objects), got " + std::to_string(count),
                       "max_objects", limits.max_objects);
  }
}

// Adds the triangles of `added`, the objects one element made, to `triangles`, the sum over
// the objects so far; `count` is how many objects there are so far, mesh files' parts
// counted one by one.
void add_triangles(const ValueReader& objects, const ValueReader& element,
                   std::span<const Object> added, std::size_t& triangles, std::size_t& count,
                   const Limits& limits) {
  for (const Object& object : added) triangles += triangle_count(object.shape);
  count += added.size();
  if (count > limits.max_objects) {
    objects.fail_limit("must make <= " + std::to_string(limits.max_objects) +
                           " objects (limit max_objects), counting each part of a mesh file, "
                           "got " +
                           std::to_string(count) + " counting up to " + element.pointer(),
                       "max_objects", limits.max_objects);
  }
  if (triangles > limits.max_triangles) {
    objects.fail_limit("must have <= " + std::to_string(limits.max_triangles) +
                           " triangles in total (limit max_triangles), got " +
                           std::to_string(triangles) + " counting up to " + element.pointer(),
                       "max_triangles", limits.max_triangles);
  }
}

}  // namespace

Mat4 parse_transform(const ValueReader& steps) { return read_every_frame(steps, compose_steps); }

Mat4 compose_steps(const ValueReader& steps) {
  const std::size_t count = steps.array_size("an array of transform steps");
  std::vector<TransformStep> parsed;
  parsed.reserve(count);
  for (std::size_t i = 0; i < count; ++i) parsed.push_back(parse_step(steps.element(i)));
  const Mat4 matrix = compose_transform(parsed);
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row)
      if (!std::isfinite(matrix[col][row]))
        steps.fail("combines to a matrix with non-finite entries (overflow)");
  const double det = linear_determinant(matrix);
  if (!(std::abs(det) >= min_determinant)) {
    steps.fail("combines to a singular matrix (determinant of its 3x3 part is " +
               format_number(det) + ", must be at least 1e-12 in magnitude)");
  }
  return matrix;
}

std::vector<Object> parse_objects(const ValueReader& objects, MaterialTable& materials,
                                  const ObjectContext& context) {
  const std::size_t count = objects.array_size("an array of objects");
  check_object_count(objects, count, context.limits);
  std::vector<Object> result;
  result.reserve(count);
  std::size_t triangles = 0;
  std::size_t made = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const ValueReader element = objects.element(i);
    const std::size_t before = result.size();
    parse_object(element, materials, context, triangles, result);
    add_triangles(objects, element, std::span(result).subspan(before), triangles, made,
                  context.limits);
  }
  return result;
}

void check_objects(const ValueReader& objects, const ObjectTexts& texts, MaterialTable& materials,
                   const ObjectContext& context) {
  const Limits& limits = context.limits;
  check_object_count(objects, texts.size(), limits);
  std::size_t triangles = 0;
  std::size_t made = 0;
  LiftedArrays lifted;
  std::vector<Object> parsed;
  for (std::size_t i = 0; i < texts.size(); ++i) {
    const std::string pointer = objects.pointer() + "/" + std::to_string(i);
    parsed.clear();
    // A mesh's arrays lifted, as parse_scene_text() does: a shape parsed before the
    // material, so that a refusal there has added nothing to the table.
    if (const auto value = texts.element_lifted(i, pointer, lifted)) {
      try {
        const ValueReader element(*value, pointer, &lifted, objects.frames());
        parse_object(element, materials, context, triangles, parsed);
        add_triangles(objects, element, parsed, triangles, made, limits);
        continue;
      } catch (const LiftedArrayRefused&) {
        // Read again below, the ordinary way, for the error's words.
        parsed.clear();
      }
    }
    const nlohmann::json value = texts.element(i);
    const ValueReader element(value, pointer, nullptr, objects.frames());
    parse_object(element, materials, context, triangles, parsed);
    add_triangles(objects, element, parsed, triangles, made, limits);
  }
}

}  // namespace tessera
