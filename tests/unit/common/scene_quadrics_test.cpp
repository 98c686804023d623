// Scene format rules for cylinders and cones: their keys, what each wrong value is told,
// and what they cost against the limits.
#include <string>

#include <gtest/gtest.h>

#include "common/scene/scene_limits_scan.hpp"
#include "scene_test_support.hpp"

namespace tessera::scene_test {
namespace {

json cylinder() {
  return {{"type", "cylinder"}, {"center", {1, 2, 3}}, {"radius", 0.5}, {"height", 4}};
}

json cone() { return {{"type", "cone"}, {"center", {-1, 0, 2}}, {"radius", 2}, {"height", 3}}; }

TEST(SceneQuadricsTest, CylinderAndConeAreRead) {
  const Scene scene = parse_scene(with(minimal_scene(), "/objects", {cylinder(), cone()}));
  ASSERT_EQ(scene.objects.size(), 2u);
  const auto& parsed_cylinder = std::get<Cylinder>(scene.objects[0].shape);
  EXPECT_EQ(parsed_cylinder.center, Vec3(1, 2, 3));
  EXPECT_EQ(parsed_cylinder.radius, 0.5);
  EXPECT_EQ(parsed_cylinder.height, 4.0);
  const auto& parsed_cone = std::get<Cone>(scene.objects[1].shape);
  EXPECT_EQ(parsed_cone.center, Vec3(-1, 0, 2));
  EXPECT_EQ(parsed_cone.radius, 2.0);
  EXPECT_EQ(parsed_cone.height, 3.0);
  // Both are solids, which refract like spheres and boxes.
  EXPECT_TRUE(is_solid(scene.objects[0]));
  EXPECT_TRUE(is_solid(scene.objects[1]));
}

TEST(SceneQuadricsTest, TakeMaterialAndTransformLikeEveryObject) {
  json object = cylinder();
  object["material"] = {{"diffuse", 0.25}};
  object["transform"] = {{{"translate", {0, 1, 0}}}};
  const Scene scene = parse_scene(with_object(object));
  EXPECT_EQ(scene.materials[scene.objects[0].material].diffuse, Color(0.25));
  EXPECT_EQ(Vec3(scene.objects[0].transform[3]), Vec3(0, 1, 0));
  object = cone();
  object["material"] = "glass";
  const Scene named = parse_scene(with(with_object(object), "/materials/glass", json::object()));
  EXPECT_EQ(named.objects[0].material, 1u);
}

TEST(SceneQuadricsTest, TypeListNamesThem) {
  EXPECT_TRUE(fails_at(with_object({{"type", "cylindre"}}), "/objects/0/type",
                       {"\"cylinder\"", "\"cone\"", "did you mean \"cylinder\"?"}));
  EXPECT_TRUE(
      fails_at(with_object({{"type", "cones"}}), "/objects/0/type", {"did you mean \"cone\"?"}));
}

// Each shape's three keys, each broken on its own: the pointer names the key.
void expect_fields_checked(const json& shape) {
  SCOPED_TRACE(shape["type"].get<std::string>());
  for (const char* key : {"center", "radius", "height"}) {
    json object = shape;
    object.erase(key);
    EXPECT_TRUE(fails_at(with_object(object), std::string("/objects/0/") + key, {"required"}));
  }
  for (const char* key : {"radius", "height"}) {
    const std::string pointer = std::string("/objects/0/") + key;
    try {
      parse_scene(with(with_object(shape), pointer, -1));
      ADD_FAILURE() << "expected an error at " << pointer;
    } catch (const SceneError& error) {
      EXPECT_EQ(std::string(error.what()), pointer + ": must be > 0, got -1");
    }
    EXPECT_TRUE(fails_at(with(with_object(shape), pointer, 0), pointer, {"must be > 0, got 0"}));
    EXPECT_TRUE(fails_at(with(with_object(shape), pointer, "1"), pointer,
                         {"must be a number, got string"}));
    EXPECT_TRUE(fails_at(with(with_object(shape), pointer, {1, 2}), pointer,
                         {"must be a number, got array"}));
  }
  EXPECT_TRUE(fails_at(with(with_object(shape), "/objects/0/center", {0, 0}), "/objects/0/center",
                       {"must be an array of 3 numbers, got an array of 2 elements"}));
  EXPECT_TRUE(fails_at(with(with_object(shape), "/objects/0/center/1", "up"), "/objects/0/center/1",
                       {"must be a number, got string"}));
  // A key of another shape, or a misspelt one, is unknown here.
  EXPECT_TRUE(fails_at(with(with_object(shape), "/objects/0/min", {0, 0, 0}), "/objects/0/min",
                       {"unknown key \"min\""}));
  EXPECT_TRUE(fails_at(with(with_object(shape), "/objects/0/hieght", 1), "/objects/0/hieght",
                       {"unknown key \"hieght\"", "did you mean \"height\"?"}));
  EXPECT_TRUE(fails_at(with(with_object(shape), "/objects/0/material", {{"ior", 0}}),
                       "/objects/0/material/ior", {"must be > 0, got 0"}));
  EXPECT_TRUE(fails_at(with(with_object(shape), "/objects/0/transform", {{{"scale", 0}}}),
                       "/objects/0/transform/0/scale", {}));
}

TEST(SceneQuadricsTest, EveryFieldIsChecked) {
  expect_fields_checked(cylinder());
  expect_fields_checked(cone());
}

TEST(SceneQuadricsTest, CostNoTriangles) {
  // Exact shapes, never tessellated: like spheres they count nothing against max_triangles,
  // in parse_scene and in the coordinator's first reading alike.
  Limits limits;
  limits.max_triangles = 12;
  const json box = {{"type", "box"}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}};
  const json scene = with(minimal_scene(), "/objects", {cylinder(), box, cone(), cylinder()});
  EXPECT_NO_THROW(parse_scene(scene, limits));
  EXPECT_NO_THROW(scan_scene_limits(scene.dump(), limits));
  limits.max_triangles = 11;
  EXPECT_TRUE(fails_at(scene, "/objects", {"limit max_triangles", "got 12"}, limits));
}

}  // namespace
}  // namespace tessera::scene_test
