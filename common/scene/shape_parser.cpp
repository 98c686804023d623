#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/scene/scene_parser_parts.hpp"

namespace tessera {
namespace {

Shape parse_sphere(const ObjectReader& object) {
  Sphere sphere;
  sphere.center = object.require("center").vec3();
  sphere.radius = object.require("radius").number(Range::above(0.0));
  return sphere;
}

// [u, v], two finite numbers.
Uv read_uv(const ValueReader& value) {
  value.expect_array_of(2, "a [u, v] pair of numbers");
  return Uv(static_cast<float>(value.element(0).number()),
            static_cast<float>(value.element(1).number()));
}

// "uvs": one [u, v] per vertex, `count` of them.
std::vector<Uv> read_uvs(const ValueReader& value, std::size_t count, std::string_view of) {
  const std::size_t size = value.array_size("an array of [u, v] pairs");
  if (size != count) {
    value.fail("must have one [u, v] per " + std::string(of) + " (" + std::to_string(count) +
               "), got " + std::to_string(size));
  }
  std::vector<Uv> uvs;
  uvs.reserve(count);
  for (std::size_t i = 0; i < count; ++i) uvs.push_back(read_uv(value.element(i)));
  return uvs;
}

Shape parse_plane(const ObjectReader& object) {
  Plane plane;
  plane.point = object.require("point").vec3();
  plane.normal = object.require("normal").direction();
  if (const auto scale = object.find("uv_scale")) {
    if (scale->json().is_array()) {
      scale->expect_array_of(2, "a number or a [u, v] pair of numbers");
      plane.uv_scale = glm::dvec2(scale->element(0).number(Range::above(0.0)),
                                  scale->element(1).number(Range::above(0.0)));
    } else {
      plane.uv_scale = glm::dvec2(scale->number(Range::above(0.0)));
    }
  }
  return plane;
}

Shape parse_box(const ObjectReader& object) {
  Box box;
  box.min = object.require("min").vec3();
  const ValueReader max = object.require("max");
  box.max = max.vec3();
  static constexpr char axes[] = {'x', 'y', 'z'};
  for (int i = 0; i < 3; ++i) {
    if (box.min[i] < box.max[i]) continue;
    max.fail(std::string("must be greater than \"min\" in every component, but max.") + axes[i] +
             " = " + format_number(box.max[i]) + " <= min." + axes[i] + " = " +
             format_number(box.min[i]));
  }
  return box;
}

Shape parse_triangle(const ObjectReader& object) {
  Triangle triangle;
  const ValueReader vertices = object.require("vertices");
  vertices.expect_array_of(3, "an array of 3 points");
  for (std::size_t i = 0; i < 3; ++i) triangle.vertices[i] = vertices.element(i).vec3();
  if (is_degenerate(triangle.vertices[0], triangle.vertices[1], triangle.vertices[2]))
    vertices.fail("must span a non-zero area, but the points are collinear or coincide");
  if (const auto normals = object.find("normals")) {
    normals->expect_array_of(3, "an array of 3 normals, one per vertex");
    std::array<Vec3, 3> unit;
    for (std::size_t i = 0; i < 3; ++i) unit[i] = normals->element(i).direction();
    triangle.normals = unit;
  }
  if (const auto uvs = object.find("uvs")) {
    const std::vector<Uv> read = read_uvs(*uvs, 3, "vertex");
    triangle.uvs = std::array<Uv, 3>{read[0], read[1], read[2]};
  }
  return triangle;
}

// A cylinder or a cone: the same three keys, under the same rules.
template <typename Axial>
Shape parse_axial(const ObjectReader& object) {
  Axial shape;
  shape.center = object.require("center").vec3();
  shape.radius = object.require("radius").number(Range::above(0.0));
  shape.height = object.require("height").number(Range::above(0.0));
  return shape;
}

// The slow path, which names what is wrong: `in_range` bounds the indices.
std::array<std::uint32_t, 3> parse_mesh_triangle(const ValueReader& value,
                                                 const std::vector<Vec3>& positions,
                                                 const IntRange& in_range) {
  value.expect_array_of(3, "an array of 3 position indices");
  std::array<std::uint32_t, 3> indices{};
  for (std::size_t k = 0; k < 3; ++k)
    indices[k] = static_cast<std::uint32_t>(value.element(k).integer(in_range));
  if (is_degenerate(positions[indices[0]], positions[indices[1]], positions[indices[2]])) {
    value.fail("is degenerate: positions " + std::to_string(indices[0]) + ", " +
               std::to_string(indices[1]) + ", " + std::to_string(indices[2]) +
               " are collinear or coincide");
  }
  return indices;
}

// The common case, with no JSON Pointer built: three non-negative JSON integers below
// `count`. Anything else (5.0, say, which is allowed) takes the slow path.
std::optional<std::array<std::uint32_t, 3>> plain_indices(const nlohmann::json& value,
                                                          std::size_t count) {
  if (!value.is_array() || value.size() != 3) return std::nullopt;
  std::array<std::uint32_t, 3> indices{};
  for (std::size_t k = 0; k < 3; ++k) {
    const nlohmann::json& index = value[k];
    if (!index.is_number_unsigned()) return std::nullopt;
    const auto v = index.get<std::uint64_t>();
    if (v >= count) return std::nullopt;
    indices[k] = static_cast<std::uint32_t>(v);
  }
  return indices;
}

// A mesh whose arrays were lifted out of the document: the same checks as below, on the
// same values; where one fails, LiftedArrayRefused sends the caller to the ordinary path,
// which words the error.
void read_lifted_positions(const LiftedTriples& lifted, Mesh& mesh) {
  const std::size_t count = lifted.numbers.size() / 3;
  if (count < 3) throw LiftedArrayRefused{};
  mesh.positions.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
    mesh.positions.emplace_back(lifted.numbers[3 * i], lifted.numbers[3 * i + 1],
                                lifted.numbers[3 * i + 2]);
}

void read_lifted_triangles(const LiftedTriples& lifted, Mesh& mesh) {
  const std::size_t count = lifted.indices.size() / 3;
  if (count == 0) throw LiftedArrayRefused{};
  mesh.triangles.reserve(count);
  const std::size_t position_count = mesh.positions.size();
  for (std::size_t t = 0; t < count; ++t) {
    std::array<std::uint32_t, 3> indices{};
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint64_t index = lifted.indices[3 * t + k];
      if (index >= position_count) throw LiftedArrayRefused{};
      indices[k] = static_cast<std::uint32_t>(index);
    }
    if (is_degenerate(mesh.positions[indices[0]], mesh.positions[indices[1]],
                      mesh.positions[indices[2]]))
      throw LiftedArrayRefused{};
    mesh.triangles.push_back(indices);
  }
}

void read_lifted_normals(const LiftedTriples& lifted, Mesh& mesh) {
  const std::size_t count = lifted.numbers.size() / 3;
  if (count != mesh.positions.size()) throw LiftedArrayRefused{};
  mesh.normals.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto unit = try_normalize(
        {lifted.numbers[3 * i], lifted.numbers[3 * i + 1], lifted.numbers[3 * i + 2]});
    if (!unit) throw LiftedArrayRefused{};
    mesh.normals.push_back(*unit);
  }
}

// Each element goes through the fast check first, and through ValueReader only when that
// fails: the same values are accepted, and the first bad one gets the same message.
Shape parse_mesh(const ObjectReader& object) {
  Mesh mesh;
  const ValueReader positions = object.require("positions");
  // Found, not required, here: the ordinary path requires it after reading the positions,
  // whose errors come first.
  const auto found_triangles = object.find("triangles");
  const auto normals = object.find("normals");
  const LiftedTriples* lifted_positions = positions.lifted();
  const LiftedTriples* lifted_triangles = found_triangles ? found_triangles->lifted() : nullptr;
  const LiftedTriples* lifted_normals = normals ? normals->lifted() : nullptr;
  if (lifted_positions != nullptr || lifted_triangles != nullptr || lifted_normals != nullptr) {
    // All of the mesh's arrays or none: the ordinary path below reads the document only.
    if (lifted_positions == nullptr || lifted_triangles == nullptr ||
        (normals && lifted_normals == nullptr))
      throw LiftedArrayRefused{};
    read_lifted_positions(*lifted_positions, mesh);
    read_lifted_triangles(*lifted_triangles, mesh);
    if (lifted_normals != nullptr) read_lifted_normals(*lifted_normals, mesh);
    if (const auto uvs = object.find("uvs"))
      mesh.uvs = read_uvs(*uvs, mesh.positions.size(), "position");
    mesh.thin = object.boolean_or("thin", false);
    return mesh;
  }
  const std::size_t position_count = positions.array_size("an array of points");
  if (position_count < 3)
    positions.fail("must have at least 3 points, got " + std::to_string(position_count));
  mesh.positions.reserve(position_count);
  for (std::size_t i = 0; i < position_count; ++i) {
    const auto point = plain_vec3(positions.json()[i]);
    mesh.positions.push_back(point ? *point : positions.element(i).vec3());
  }

  const ValueReader triangles = object.require("triangles");
  const std::size_t index_triples = triangles.array_size("an array of triangles");
  if (index_triples == 0) triangles.fail("must have at least 1 triangle, got 0");
  mesh.triangles.reserve(index_triples);
  const IntRange in_range{0, static_cast<std::int64_t>(position_count) - 1,
                          "the mesh has " + std::to_string(position_count) + " positions"};
  for (std::size_t t = 0; t < index_triples; ++t) {
    const auto indices = plain_indices(triangles.json()[t], position_count);
    if (indices && !is_degenerate(mesh.positions[(*indices)[0]], mesh.positions[(*indices)[1]],
                                  mesh.positions[(*indices)[2]]))
      mesh.triangles.push_back(*indices);
    else
      mesh.triangles.push_back(parse_mesh_triangle(triangles.element(t), mesh.positions, in_range));
  }

  if (normals) {
    const std::size_t normal_count = normals->array_size("an array of normals");
    if (normal_count != position_count) {
      normals->fail("must have one normal per position (" + std::to_string(position_count) +
                    "), got " + std::to_string(normal_count));
    }
    mesh.normals.reserve(normal_count);
    for (std::size_t i = 0; i < normal_count; ++i) {
      const auto raw = plain_vec3(normals->json()[i]);
      const auto unit = raw ? try_normalize(*raw) : std::nullopt;
      mesh.normals.push_back(unit ? *unit : normals->element(i).direction());
    }
  }
  if (const auto uvs = object.find("uvs")) mesh.uvs = read_uvs(*uvs, position_count, "position");
  mesh.thin = object.boolean_or("thin", false);
  return mesh;
}

constexpr std::string_view sphere_keys[] = {"center", "radius"};
constexpr std::string_view plane_keys[] = {"point", "normal", "uv_scale"};
constexpr std::string_view box_keys[] = {"min", "max"};
constexpr std::string_view triangle_keys[] = {"vertices", "normals", "uvs"};
constexpr std::string_view mesh_keys[] = {"positions", "triangles", "normals", "uvs", "thin"};
constexpr std::string_view axial_keys[] = {"center", "radius", "height"};  // cylinder, cone

constexpr ShapeType types[] = {
    {"sphere", sphere_keys, parse_sphere},
    {"plane", plane_keys, parse_plane},
    {"box", box_keys, parse_box},
    {"triangle", triangle_keys, parse_triangle},
    {"mesh", mesh_keys, parse_mesh},
    {"cylinder", axial_keys, parse_axial<Cylinder>},
    {"cone", axial_keys, parse_axial<Cone>},
};

struct TriangleCount {
  std::size_t operator()(const Box&) const { return 12; }
  std::size_t operator()(const Triangle&) const { return 1; }
  std::size_t operator()(const Mesh& mesh) const { return mesh.triangles.size(); }
  std::size_t operator()(const auto&) const { return 0; }
};

}  // namespace

// Zero area up to rounding, relative to the triangle's own size so that the test means
// the same for a scene modelled in millimetres and one modelled in kilometres.
bool is_degenerate(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a;
  const Vec3 e2 = c - a;
  const double scale = std::max({std::abs(e1.x), std::abs(e1.y), std::abs(e1.z), std::abs(e2.x),
                                 std::abs(e2.y), std::abs(e2.z)});
  if (!(scale > 0.0) || !std::isfinite(scale)) return true;
  return glm::length(glm::cross(e1 / scale, e2 / scale)) <= 1e-12;
}

std::span<const ShapeType> shape_types() { return types; }

std::size_t triangle_count(const Shape& shape) { return std::visit(TriangleCount{}, shape); }

}  // namespace tessera
