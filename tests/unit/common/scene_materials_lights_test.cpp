// Scene format rules for named and inline materials and for lights.
#include <string>
#include <variant>

#include <gtest/gtest.h>

#include "scene_test_support.hpp"

namespace tessera::scene_test {
namespace {

// --- materials ---

json with_material(const std::string& name, json material) {
  return with(minimal_scene(), "/materials", {{name, std::move(material)}});
}

TEST(SceneMaterialsTest, Shape) {
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/materials", json::array()), "/materials",
                       {"must be an object mapping material names to materials, got array"}));
  EXPECT_TRUE(fails_at(with_material("red", 1), "/materials/red",
                       {"must be a material object, got number"}));
  EXPECT_TRUE(fails_at(with_material("red", {{"difuse", 1}}), "/materials/red/difuse",
                       {"unknown key \"difuse\"", "did you mean \"diffuse\"?"}));
}

TEST(SceneMaterialsTest, FieldRules) {
  EXPECT_TRUE(fails_at(with_material("m", {{"emission", {1, -1, 1}}}), "/materials/m/emission/1",
                       {"must be >= 0"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"ambient", "red"}}), "/materials/m/ambient",
                       {"must be a color"}));
  EXPECT_TRUE(
      fails_at(with_material("m", {{"diffuse", -0.1}}), "/materials/m/diffuse", {"must be >= 0"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"specular", {1, 1}}}), "/materials/m/specular",
                       {"must be a color"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"reflection", {0, 0, -2}}}),
                       "/materials/m/reflection/2", {"must be >= 0"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"transmission", true}}), "/materials/m/transmission",
                       {"must be a color", "got boolean"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"shininess", -1}}), "/materials/m/shininess",
                       {"must be >= 0, got -1"}));
  EXPECT_TRUE(
      fails_at(with_material("m", {{"ior", 0}}), "/materials/m/ior", {"must be > 0, got 0"}));
}

TEST(SceneMaterialsTest, Checker) {
  EXPECT_TRUE(fails_at(with_material("m", {{"checker", json::object()}}),
                       "/materials/m/checker/size", {"required"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"checker", {{"size", 0}}}}),
                       "/materials/m/checker/size", {"must be > 0, got 0"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"checker", {{"size", 1}, {"color", 1}}}}),
                       "/materials/m/checker/color", {"unknown key"}));
  EXPECT_TRUE(fails_at(with_material("m", {{"checker", {{"size", 1}, {"diffuse", -1}}}}),
                       "/materials/m/checker/diffuse", {"must be >= 0"}));

  const Scene defaults =
      parse_scene(with_material("m", {{"ambient", 0.3}, {"checker", {{"size", 2}}}}));
  ASSERT_TRUE(defaults.materials[1].checker.has_value());
  EXPECT_EQ(defaults.materials[1].checker->size, 2.0);
  EXPECT_EQ(defaults.materials[1].checker->ambient, Color(0.3));
  EXPECT_EQ(defaults.materials[1].checker->diffuse, Color(0.8));

  const Scene given = parse_scene(
      with_material("m", {{"checker", {{"size", 0.5}, {"ambient", {1, 0, 0}}, {"diffuse", 0}}}}));
  EXPECT_EQ(given.materials[1].checker->ambient, Color(1, 0, 0));
  EXPECT_EQ(given.materials[1].checker->diffuse, Color(0));
}

TEST(SceneMaterialsTest, ReflectionDefaultsToSpecular) {
  const Scene scene =
      parse_scene(with(with_material("shiny", {{"specular", {0.5, 0.6, 0.7}}}), "/materials/mirror",
                       {{"specular", 0.2}, {"reflection", 1}}));
  ASSERT_EQ(scene.materials.size(), 3u);
  EXPECT_EQ(scene.materials[2].reflection, Color(0.5, 0.6, 0.7));  // "shiny" sorts after "mirror"
  EXPECT_EQ(scene.materials[1].reflection, Color(1.0));
}

TEST(SceneMaterialsTest, PointerEscapesNames) {
  EXPECT_TRUE(fails_at(with_material("glass/blue~2", {{"ior", -1}}),
                       "/materials/glass~1blue~02/ior", {"must be > 0, got -1"}));
}

TEST(SceneMaterialsTest, CountLimit) {
  Limits limits;
  limits.max_materials = 1;
  const json two = with(with_material("a", json::object()), "/materials/b", json::object());
  EXPECT_TRUE(
      fails_at(two, "/materials", {"must have <= 1 entries (limit max_materials), got 2"}, limits));
  // Inline materials count too.
  json inline_too =
      with(with_material("a", json::object()), "/objects", json::array({sphere(), sphere()}));
  inline_too["objects"][1]["material"] = json::object();
  EXPECT_TRUE(fails_at(inline_too, "/objects/1/material", {"limit max_materials"}, limits));
}

// --- lights ---

TEST(SceneLightsTest, Shape) {
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/lights", json::object()), "/lights",
                       {"must be an array of lights, got object"}));
  EXPECT_TRUE(fails_at(with_light("sun"), "/lights/0", {"must be a light object, got string"}));
  EXPECT_TRUE(fails_at(with_light({{"position", {0, 0, 0}}}), "/lights/0/type", {"required"}));
  EXPECT_TRUE(fails_at(with_light({{"type", "spott"}}), "/lights/0/type",
                       {"must be one of \"point\", \"directional\", \"spot\", got \"spott\"",
                        "did you mean \"spot\"?"}));
  EXPECT_TRUE(fails_at(with_light({{"type", 3}}), "/lights/0/type", {"must be a string"}));
}

TEST(SceneLightsTest, Point) {
  EXPECT_TRUE(fails_at(with_light({{"type", "point"}}), "/lights/0/position", {"required"}));
  EXPECT_TRUE(fails_at(with_light({{"type", "point"}, {"position", {0, 0, 0}}, {"cutoff", 10}}),
                       "/lights/0/cutoff", {"unknown key \"cutoff\""}));
  EXPECT_TRUE(fails_at(with_light({{"type", "point"}, {"position", {0, 0, 0}}, {"intensity", -1}}),
                       "/lights/0/intensity", {"must be >= 0"}));

  const Scene scene = parse_scene(with_light({{"type", "point"}, {"position", {1, 2, 3}}}));
  const auto& light = std::get<PointLight>(scene.lights.at(0));
  EXPECT_EQ(light.position, Vec3(1, 2, 3));
  EXPECT_EQ(light.intensity, Color(1.0));
  EXPECT_EQ(light.attenuation.constant, 1.0);
  EXPECT_EQ(light.attenuation.linear, 0.0);
  EXPECT_EQ(light.attenuation.quadratic, 0.0);
}

TEST(SceneLightsTest, Attenuation) {
  const json point = {{"type", "point"}, {"position", {0, 0, 0}}};
  EXPECT_TRUE(fails_at(with(with_light(point), "/lights/0/attenuation", {0, 0, 0}),
                       "/lights/0/attenuation", {"must not be all zero", "infinitely bright"}));
  EXPECT_TRUE(fails_at(with(with_light(point), "/lights/0/attenuation", {1, 0, -1}),
                       "/lights/0/attenuation/2", {"must be >= 0, got -1"}));
  EXPECT_TRUE(fails_at(with(with_light(point), "/lights/0/attenuation", {1, 0}),
                       "/lights/0/attenuation", {"must be an array of 3 numbers"}));
  const Scene scene = parse_scene(with(with_light(point), "/lights/0/attenuation", {0, 0, 2}));
  EXPECT_EQ(std::get<PointLight>(scene.lights[0]).attenuation.quadratic, 2.0);
}

TEST(SceneLightsTest, Directional) {
  EXPECT_TRUE(fails_at(with_light({{"type", "directional"}}), "/lights/0/direction", {"required"}));
  EXPECT_TRUE(fails_at(with_light({{"type", "directional"}, {"direction", {0, 0, 0}}}),
                       "/lights/0/direction", {"non-zero"}));
  const Scene scene = parse_scene(
      with_light({{"type", "directional"}, {"direction", {0, -3, 0}}, {"intensity", {1, 0.5, 0}}}));
  const auto& light = std::get<DirectionalLight>(scene.lights.at(0));
  EXPECT_EQ(light.direction, Vec3(0, -1, 0));
  EXPECT_EQ(light.intensity, Color(1, 0.5, 0));
}

TEST(SceneLightsTest, Spot) {
  const json spot = {{"type", "spot"}, {"position", {0, 4, 0}}, {"direction", {0, -2, 0}}};
  EXPECT_TRUE(fails_at(with(with_light(spot), "/lights/0/cutoff", 0), "/lights/0/cutoff",
                       {"must be in (0, 90], got 0"}));
  EXPECT_TRUE(fails_at(with(with_light(spot), "/lights/0/cutoff", 90.5), "/lights/0/cutoff",
                       {"must be in (0, 90], got 90.5"}));
  EXPECT_TRUE(fails_at(with(with_light(spot), "/lights/0/exponent", -1), "/lights/0/exponent",
                       {"must be >= 0, got -1"}));
  EXPECT_TRUE(fails_at(with(with_light(spot), "/lights/0/direction", {0, 0, 0}),
                       "/lights/0/direction", {"non-zero"}));
  json no_position = spot;
  no_position.erase("position");
  EXPECT_TRUE(fails_at(with_light(no_position), "/lights/0/position", {"required"}));

  const auto defaults = std::get<SpotLight>(parse_scene(with_light(spot)).lights.at(0));
  EXPECT_EQ(defaults.direction, Vec3(0, -1, 0));
  EXPECT_EQ(defaults.cutoff_degrees, 90.0);
  EXPECT_EQ(defaults.exponent, 1.0);
  EXPECT_EQ(defaults.intensity, Color(1.0));
  EXPECT_EQ(defaults.attenuation.constant, 1.0);
}

TEST(SceneLightsTest, CountLimit) {
  Limits limits;
  limits.max_lights = 1;
  const json light = {{"type", "directional"}, {"direction", {0, -1, 0}}};
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/lights", {light, light}), "/lights",
                       {"must have <= 1 elements (limit max_lights), got 2"}, limits));
}

}  // namespace
}  // namespace tessera::scene_test
