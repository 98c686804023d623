// Scene format rules for objects, their shapes, materials and transforms, plus the edit
// distance behind "did you mean" and the transform arithmetic.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/scene/transform.hpp"
#include "common/text/suggest.hpp"
#include "scene_test_support.hpp"

namespace tessera::scene_test {
namespace {

json square_mesh() {
  return {{"type", "mesh"},
          {"positions", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
          {"triangles", {{0, 1, 2}, {0, 2, 3}}}};
}

json with_transform(json steps) {
  json object = sphere();
  object["transform"] = std::move(steps);
  return with_object(std::move(object));
}

// --- objects in general ---

TEST(SceneObjectsTest, Shape) {
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/objects", json::object()), "/objects",
                       {"must be an array of objects, got object"}));
  EXPECT_TRUE(fails_at(with_object(1), "/objects/0", {"must be an object", "got number"}));
  EXPECT_TRUE(fails_at(with_object({{"radius", 1}}), "/objects/0/type", {"required"}));
  EXPECT_TRUE(fails_at(with_object({{"type", "sphre"}}), "/objects/0/type",
                       {"must be one of \"sphere\", \"plane\", \"box\", \"triangle\", \"mesh\"",
                        "got \"sphre\"", "did you mean \"sphere\"?"}));
}

TEST(SceneObjectsTest, UnknownKeySuggestsKnownOne) {
  const json object = {{"type", "sphere"}, {"center", {0, 0, 0}}, {"raduis", 1}};
  EXPECT_TRUE(fails_at(with_object(object), "/objects/0/raduis",
                       {"unknown key \"raduis\"", "did you mean \"radius\"?"}));
  // Keys of other shape types are unknown here too.
  EXPECT_TRUE(fails_at(with(with_object(sphere()), "/objects/0/normal", {0, 1, 0}),
                       "/objects/0/normal", {"unknown key \"normal\""}));
}

TEST(SceneObjectsTest, MaterialReference) {
  json scene = with(with_object(sphere()), "/materials/glass", json::object());
  EXPECT_TRUE(fails_at(with(scene, "/objects/0/material", "glas"), "/objects/0/material",
                       {"unknown material \"glas\"", "did you mean \"glass\"?"}));
  EXPECT_TRUE(fails_at(with(scene, "/objects/0/material", "steel"), "/objects/0/material",
                       {"unknown material \"steel\"", "defined materials: \"glass\""}));
  EXPECT_TRUE(fails_at(with(with_object(sphere()), "/objects/0/material", "glass"),
                       "/objects/0/material", {"defines no named materials"}));
  EXPECT_TRUE(fails_at(with(scene, "/objects/0/material", 2), "/objects/0/material",
                       {"must be a material name (string) or a material object, got number"}));
  EXPECT_TRUE(fails_at(with(scene, "/objects/0/material", {{"ior", -1}}), "/objects/0/material/ior",
                       {"must be > 0, got -1"}));
  EXPECT_TRUE(fails_at(with(scene, "/objects/0/material", {{"shinyness", 1}}),
                       "/objects/0/material/shinyness", {"did you mean \"shininess\"?"}));
  EXPECT_EQ(parse_scene(with(scene, "/objects/0/material", "glass")).objects[0].material, 1u);
}

TEST(SceneObjectsTest, CountLimits) {
  Limits limits;
  limits.max_objects = 1;
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/objects", {sphere(), sphere()}), "/objects",
                       {"must have <= 1 elements (limit max_objects), got 2"}, limits));

  limits = Limits{};
  limits.max_triangles = 13;
  const json box = {{"type", "box"}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}};
  const json triangle = {{"type", "triangle"}, {"vertices", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}};
  EXPECT_NO_THROW(parse_scene(with(minimal_scene(), "/objects", {box, triangle}), limits));
  EXPECT_TRUE(fails_at(
      with(minimal_scene(), "/objects", {box, triangle, sphere(), square_mesh()}), "/objects",
      {"must have <= 13 triangles in total (limit max_triangles), got 15", "/objects/3"}, limits));
}

// --- shapes ---

TEST(SceneShapesTest, Sphere) {
  json object = sphere();
  object["radius"] = -1;
  try {
    parse_scene(with_object(object));
    FAIL() << "expected an error";
  } catch (const SceneError& error) {
    EXPECT_STREQ(error.what(), "/objects/0/radius: must be > 0, got -1");
  }
  EXPECT_TRUE(fails_at(with(with_object(sphere()), "/objects/0/radius", 0), "/objects/0/radius",
                       {"must be > 0, got 0"}));
  object = sphere();
  object.erase("center");
  EXPECT_TRUE(fails_at(with_object(object), "/objects/0/center", {"required"}));
  object = sphere();
  object.erase("radius");
  EXPECT_TRUE(fails_at(with_object(object), "/objects/0/radius", {"required"}));
}

TEST(SceneShapesTest, Plane) {
  const json plane = {{"type", "plane"}, {"point", {0, -1, 0}}, {"normal", {0, 0, 0}}};
  EXPECT_TRUE(fails_at(with_object(plane), "/objects/0/normal", {"must be a non-zero vector"}));
  const Scene scene = parse_scene(with(with_object(plane), "/objects/0/normal", {3, 0, 4}));
  const auto& parsed = std::get<Plane>(scene.objects[0].shape);
  EXPECT_EQ(parsed.point, Vec3(0, -1, 0));
  EXPECT_NEAR(parsed.normal.x, 0.6, 1e-15);
  EXPECT_NEAR(parsed.normal.z, 0.8, 1e-15);
}

TEST(SceneShapesTest, Box) {
  const json box = {{"type", "box"}, {"min", {0, 2, 0}}, {"max", {1, 1, 1}}};
  EXPECT_TRUE(
      fails_at(with_object(box), "/objects/0/max",
               {"must be greater than \"min\" in every component", "max.y = 1", "min.y = 2"}));
  EXPECT_TRUE(fails_at(with(with_object(box), "/objects/0/max", {1, 2, 1}), "/objects/0/max",
                       {"max.y = 2 <= min.y = 2"}));
  const Scene scene = parse_scene(with(with_object(box), "/objects/0/max", {1, 3, 1}));
  EXPECT_EQ(std::get<Box>(scene.objects[0].shape).max, Vec3(1, 3, 1));
}

TEST(SceneShapesTest, Triangle) {
  const json triangle = {{"type", "triangle"}, {"vertices", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}};
  EXPECT_TRUE(fails_at(with(with_object(triangle), "/objects/0/vertices", {{0, 0, 0}, {1, 0, 0}}),
                       "/objects/0/vertices", {"must be an array of 3 points"}));
  EXPECT_TRUE(fails_at(with(with_object(triangle), "/objects/0/vertices/2", {2, 0, 0}),
                       "/objects/0/vertices", {"non-zero area", "collinear"}));
  EXPECT_TRUE(fails_at(with(with_object(triangle), "/objects/0/vertices/1/0", "1"),
                       "/objects/0/vertices/1/0", {"must be a number, got string"}));
  EXPECT_TRUE(fails_at(with(with_object(triangle), "/objects/0/normals", {{0, 0, 1}, {0, 0, 0}}),
                       "/objects/0/normals", {"must be an array of 3 normals"}));
  EXPECT_TRUE(
      fails_at(with(with_object(triangle), "/objects/0/normals", {{0, 0, 1}, {0, 0, 0}, {0, 0, 1}}),
               "/objects/0/normals/1", {"non-zero"}));

  // Degeneracy is relative to the triangle's size: a tiny triangle is still a triangle.
  EXPECT_NO_THROW(parse_scene(
      with(with_object(triangle), "/objects/0/vertices", {{0, 0, 0}, {1e-9, 0, 0}, {0, 1e-9, 0}})));
  const Scene scene = parse_scene(
      with(with_object(triangle), "/objects/0/normals", {{0, 0, 2}, {0, 0, 1}, {0, 3, 4}}));
  const auto& normals = std::get<Triangle>(scene.objects[0].shape).normals;
  ASSERT_TRUE(normals.has_value());
  EXPECT_EQ((*normals)[0], Vec3(0, 0, 1));
  EXPECT_NEAR((*normals)[2].y, 0.6, 1e-15);
}

TEST(SceneShapesTest, MeshIndices) {
  const json mesh = with_object(square_mesh());
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/triangles/1/2", 4), "/objects/0/triangles/1/2",
                       {"must be <= 3 (the mesh has 4 positions), got 4"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/triangles/0/0", -1), "/objects/0/triangles/0/0",
                       {"must be >= 0, got -1"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/triangles/0/1", 1.5), "/objects/0/triangles/0/1",
                       {"must be an integer, got 1.5"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/triangles/0", {0, 1}), "/objects/0/triangles/0",
                       {"must be an array of 3 position indices"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/triangles/1", {0, 2, 2}), "/objects/0/triangles/1",
                       {"is degenerate", "positions 0, 2, 2"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/triangles", json::array()), "/objects/0/triangles",
                       {"must have at least 1 triangle"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/positions", {{0, 0, 0}, {1, 0, 0}}),
                       "/objects/0/positions", {"must have at least 3 points, got 2"}));
  json no_triangles = square_mesh();
  no_triangles.erase("triangles");
  EXPECT_TRUE(fails_at(with_object(no_triangles), "/objects/0/triangles", {"required"}));
}

// Mesh elements are read by a fast check that builds no JSON Pointer, and only what it
// refuses goes through the full rules: those still parse, or fail at their own pointer.
TEST(SceneShapesTest, MeshElementsOffTheFastPathParseOrFailAtTheirPointer) {
  const json mesh = with_object(square_mesh());
  const Scene scene = parse_scene(with(mesh, "/objects/0/triangles/1", {0.0, 2, 3.0}));
  EXPECT_EQ(std::get<Mesh>(scene.objects[0].shape).triangles[1],
            (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/positions/3/2", "z"), "/objects/0/positions/3/2",
                       {"must be a number, got string"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/positions/2", {1, 1}), "/objects/0/positions/2",
                       {"must be an array of 3 numbers"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/triangles/1/0", 4000000000u),
                       "/objects/0/triangles/1/0", {"must be <= 3 (the mesh has 4 positions)"}));
  const Scene huge = parse_scene(
      with(mesh, "/objects/0/normals", {{1e308, 1e308, 0}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}}));
  EXPECT_NEAR(std::get<Mesh>(huge.objects[0].shape).normals[0].x, std::sqrt(0.5), 1e-15);
}

TEST(SceneShapesTest, MeshNormalsAndThin) {
  const json mesh = with_object(square_mesh());
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/normals", {{0, 0, 1}}), "/objects/0/normals",
                       {"must have one normal per position (4), got 1"}));
  EXPECT_TRUE(
      fails_at(with(mesh, "/objects/0/normals", {{0, 0, 1}, {0, 0, 1}, {0, 0, 0}, {0, 0, 1}}),
               "/objects/0/normals/2", {"non-zero"}));
  EXPECT_TRUE(fails_at(with(mesh, "/objects/0/thin", 1), "/objects/0/thin",
                       {"must be a boolean, got number"}));

  const Scene scene =
      parse_scene(with(mesh, "/objects/0/normals", {{0, 0, 5}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}}));
  const auto& parsed = std::get<Mesh>(scene.objects[0].shape);
  EXPECT_FALSE(parsed.thin);
  ASSERT_EQ(parsed.normals.size(), 4u);
  EXPECT_EQ(parsed.normals[0], Vec3(0, 0, 1));
  EXPECT_EQ(parsed.positions[2], Vec3(1, 1, 0));
}

// --- transforms ---

TEST(SceneTransformsTest, StepShape) {
  EXPECT_TRUE(fails_at(with_transform(json::object()), "/objects/0/transform",
                       {"must be an array of transform steps, got object"}));
  EXPECT_TRUE(fails_at(with_transform({"scale"}), "/objects/0/transform/0",
                       {"must be a transform step object, got string"}));
  EXPECT_TRUE(fails_at(
      with_transform({json::object()}), "/objects/0/transform/0",
      {"must have exactly one of \"translate\", \"rotate\", \"scale\", \"matrix\"", "got 0 keys"}));
  EXPECT_TRUE(fails_at(with_transform({{{"scale", 2}, {"translate", {1, 0, 0}}}}),
                       "/objects/0/transform/0", {"must have exactly one of", "got 2 keys"}));
  EXPECT_TRUE(fails_at(with_transform({{{"translat", {1, 0, 0}}}}),
                       "/objects/0/transform/0/translat",
                       {"unknown key", "did you mean \"translate\"?"}));
}

TEST(SceneTransformsTest, StepRules) {
  EXPECT_TRUE(fails_at(with_transform({{{"translate", {1, 0}}}}),
                       "/objects/0/transform/0/translate", {"must be an array of 3 numbers"}));
  EXPECT_TRUE(fails_at(with_transform({{{"rotate", {{"axis", {0, 1, 0}}}}}}),
                       "/objects/0/transform/0/rotate/degrees", {"required"}));
  EXPECT_TRUE(fails_at(with_transform({{{"rotate", {{"axis", {0, 0, 0}}, {"degrees", 9}}}}}),
                       "/objects/0/transform/0/rotate/axis", {"non-zero"}));
  EXPECT_TRUE(fails_at(with_transform({{{"rotate", {{"axis", {0, 1, 0}}, {"angle", 9}}}}}),
                       "/objects/0/transform/0/rotate/angle", {"unknown key"}));
  EXPECT_TRUE(fails_at(with_transform({{{"scale", 0}}}), "/objects/0/transform/0/scale",
                       {"must be non-zero, got 0"}));
  EXPECT_TRUE(fails_at(with_transform({{{"scale", {1, 0, 1}}}}), "/objects/0/transform/0/scale/1",
                       {"must be non-zero"}));
  EXPECT_TRUE(fails_at(with_transform({{{"scale", "big"}}}), "/objects/0/transform/0/scale",
                       {"must be a number or an array of 3 numbers, got string"}));
}

json row_major(std::array<double, 16> values) { return json(values); }

TEST(SceneTransformsTest, MatrixRules) {
  EXPECT_TRUE(fails_at(with_transform({{{"matrix", {1, 0, 0, 1}}}}),
                       "/objects/0/transform/0/matrix",
                       {"must be an array of 16 numbers", "got an array of 4 elements"}));
  EXPECT_TRUE(fails_at(
      with_transform({{{"matrix", row_major({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1})}}}),
      "/objects/0/transform/0/matrix", {"must be affine", "got [0, 0, 1, 1]"}));
  EXPECT_TRUE(fails_at(
      with_transform({{{"matrix", row_major({1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1})}}}),
      "/objects/0/transform/0/matrix", {"must be invertible"}));

  const Scene scene = parse_scene(
      with_transform({{{"matrix", row_major({2, 0, 0, 5, 0, 1, 0, 6, 0, 0, 1, 7, 0, 0, 0, 1})}}}));
  const Mat4& m = scene.objects[0].transform;
  EXPECT_EQ(m * glm::dvec4(1, 1, 1, 1), glm::dvec4(7, 7, 8, 1));
}

TEST(SceneTransformsTest, SingularProductIsRejected) {
  // Each step alone is fine; together they squash space below the threshold.
  EXPECT_TRUE(fails_at(with_transform({{{"scale", 1e-3}}, {{"scale", 1e-3}}}),
                       "/objects/0/transform", {"singular"}));
  EXPECT_NO_THROW(parse_scene(with_transform({{{"scale", 1e-3}}})));
  EXPECT_TRUE(fails_at(with_transform({{{"scale", 1e200}}, {{"scale", 1e200}}}),
                       "/objects/0/transform", {"non-finite"}));
}

TEST(SceneTransformsTest, StepsApplyInOrder) {
  const auto transform_of = [](json steps) {
    return parse_scene(with_transform(std::move(steps))).objects[0].transform;
  };
  const glm::dvec4 x(1, 0, 0, 1);
  EXPECT_EQ(transform_of({{{"scale", 2}}, {{"translate", {1, 0, 0}}}}) * x, glm::dvec4(3, 0, 0, 1));
  EXPECT_EQ(transform_of({{{"translate", {1, 0, 0}}}, {{"scale", 2}}}) * x, glm::dvec4(4, 0, 0, 1));
  EXPECT_EQ(transform_of({{{"scale", {1, 2, 3}}}}) * glm::dvec4(1, 1, 1, 1),
            glm::dvec4(1, 2, 3, 1));
  // Right-hand rule about +y takes +x to -z; quarter turns are exact.
  EXPECT_EQ(transform_of({{{"rotate", {{"axis", {0, 5, 0}}, {"degrees", 90}}}}}) * x,
            glm::dvec4(0, 0, -1, 1));
  EXPECT_EQ(transform_of(json::array()), Mat4(1.0));
}

TEST(TransformTest, ComposeAndRotate) {
  const std::vector<TransformStep> steps = {Rotate{Vec3(0, 0, 1), 90.0}, Translate{Vec3(0, 0, 2)}};
  EXPECT_EQ(compose_transform(steps) * glm::dvec4(1, 0, 0, 1), glm::dvec4(0, 1, 2, 1));
  const Mat4 r = step_matrix(Rotate{Vec3(1, 1, 1), 120.0});
  const glm::dvec4 rotated = r * glm::dvec4(1, 0, 0, 1);
  EXPECT_NEAR(rotated.x, 0.0, 1e-15);
  EXPECT_NEAR(rotated.y, 1.0, 1e-15);
  EXPECT_NEAR(rotated.z, 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(linear_determinant(step_matrix(Scale{Vec3(2, 3, 4)})), 24.0);
}

// --- suggestions ---

TEST(SuggestTest, EditDistance) {
  EXPECT_EQ(edit_distance("radius", "radius"), 0u);
  EXPECT_EQ(edit_distance("raduis", "radius"), 1u);  // a swap is one edit
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("abc", ""), 3u);
}

TEST(SuggestTest, ClosestMatch) {
  const std::vector<std::string_view> keys = {"min", "max", "radius"};
  EXPECT_EQ(closest_match("mxa", keys), "max");
  EXPECT_EQ(closest_match("radus", keys), "radius");
  EXPECT_EQ(closest_match("rdus", keys), "radius");
  EXPECT_EQ(closest_match("RADIUS", keys), "radius");  // case is ignored
  EXPECT_FALSE(closest_match("width", keys).has_value());
  // Short words need to be within one edit.
  EXPECT_FALSE(closest_match("mid", std::vector<std::string_view>{"max"}).has_value());
}

}  // namespace
}  // namespace tessera::scene_test
