// Scene format rules for the document, image, camera, render settings and colors, and a
// complete scene; materials and lights are in scene_materials_lights_test.cpp, objects
// and transforms in scene_objects_test.cpp.
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <variant>

#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "common/scene/json_fast_parse.hpp"
#include "scene_test_support.hpp"

namespace tessera::scene_test {
namespace {

// --- the document and its JSON text ---

TEST(SceneDocumentTest, MustBeAnObject) {
  EXPECT_TRUE(fails_at(json::array(), "", {"must be a JSON object", "got array"}));
}

TEST(SceneDocumentTest, SyntaxErrorNamesLineAndColumn) {
  try {
    parse_scene_text("{\n  \"image\": ,\n}");
    FAIL() << "expected a syntax error";
  } catch (const SceneError& error) {
    EXPECT_EQ(error.pointer(), "");
    EXPECT_NE(error.detail().find("invalid JSON at line 2, column 12"), std::string::npos)
        << error.what();
  }
}

TEST(SceneDocumentTest, ColumnsCountCharactersNotBytes) {
  try {
    parse_scene_text("{\"é\": x}");
    FAIL() << "expected a syntax error";
  } catch (const SceneError& error) {
    EXPECT_NE(error.detail().find("line 1, column 7"), std::string::npos) << error.what();
  }
}

std::string nested_arrays(int depth) {
  return "{\"x\": " + std::string(static_cast<std::size_t>(depth - 1), '[') +
         std::string(static_cast<std::size_t>(depth - 1), ']') + "}";
}

TEST(SceneDocumentTest, RejectsNestingDeeperThan64) {
  try {
    parse_scene_text(nested_arrays(65));
    FAIL() << "expected a nesting error";
  } catch (const SceneError& error) {
    EXPECT_EQ(error.pointer(), "");
    EXPECT_NE(error.detail().find("deeper than 64 levels"), std::string::npos) << error.what();
  }
}

TEST(SceneDocumentTest, AcceptsNestingOf64AndIgnoresBracketsInStrings) {
  // Gets past the JSON stage, so the scene rules complain instead.
  try {
    parse_scene_text(nested_arrays(64));
    FAIL() << "expected a scene error";
  } catch (const SceneError& error) {
    EXPECT_EQ(error.pointer(), "/x");
  }
  const std::string brackets(100, '[');
  EXPECT_NO_THROW(
      parse_scene_text(with(minimal_scene(), "/materials/" + brackets, json::object()).dump()));
}

// nlohmann refuses a literal beyond the range of double rather than storing infinity.
TEST(SceneDocumentTest, HugeLiteralIsAJsonError) {
  const std::string text = "{\"image\": {\"width\": 4, \"height\": 3},\n \"background\": 1e999}";
  try {
    parse_scene_text(text);
    FAIL() << "expected an error";
  } catch (const SceneError& error) {
    EXPECT_EQ(error.pointer(), "");
    EXPECT_NE(error.detail().find("invalid JSON at line 2, column 20: number overflow"),
              std::string::npos)
        << error.what();
  }
}

// simdjson parses first; whatever it accepts must be exactly what nlohmann makes of the
// same text, and what it refuses goes to nlohmann, which words the error or accepts it.
TEST(SceneDocumentTest, TheFastParserAgreesWithNlohmannOrStepsAside) {
  const char* const texts[] = {"0",
                               "-0.0",
                               "5",
                               "-5",
                               "1.5",
                               "0.1e1",
                               "1E+2",
                               "1e-320",
                               "2.2250738585072014e-308",
                               "0.30000000000000004",
                               "9007199254740993",
                               "18446744073709551615",
                               "-9223372036854775808",
                               "true",
                               "null",
                               "\"\"",
                               "\"\\u0000\"",
                               "\"\\ud834\\udd1e\"",
                               "\"\\/\\b\\f\\n\\r\\t\"",
                               "[\"\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\"]",
                               " \t\r\n{ \"a\" : [ 1 , { } , [ ] ] } \n",
                               "{\"a\": 1, \"a\": 2}",
                               "{\"b\": 1, \"a\": {\"a\": [null, false]}}",
                               "[[1,2,3],[4,5,6]]"};
  for (const char* text : texts) {
    const auto fast = parse_json_fast(text, 64);
    ASSERT_TRUE(fast.has_value()) << text;
    const json slow = json::parse(text);
    EXPECT_EQ(*fast, slow) << text;
    EXPECT_EQ(fast->dump(), slow.dump()) << text;
    EXPECT_EQ(fast->type(), slow.type()) << text;
  }
  // Its depth limit is the pre-scan's, which parse_json_text() runs only where it refuses.
  EXPECT_TRUE(parse_json_fast(nested_arrays(64), 64).has_value());
  EXPECT_FALSE(parse_json_fast(nested_arrays(65), 64).has_value());
  EXPECT_TRUE(parse_json_fast("-0", 64).value().is_number_unsigned());  // nlohmann: signed 0
  EXPECT_EQ(parse_json_fast("-0", 64).value(), json::parse("-0"));

  // Refused here; nlohmann accepts the first three and refuses the rest.
  const char* const refused[] = {"18446744073709551616",
                                 "-9223372036854775809",
                                 "\xef\xbb\xbf{}",
                                 "1e400",
                                 "",
                                 "{} x",
                                 "[1,]",
                                 "01",
                                 "1.",
                                 "-",
                                 "\"\\ud800\"",
                                 "\"a\x01\"",
                                 "\"\xff\"",
                                 "{'a': 1}",
                                 "[NaN]",
                                 "+1"};
  for (const char* text : refused) EXPECT_FALSE(parse_json_fast(text, 64).has_value()) << text;
  EXPECT_EQ(parse_json_text("18446744073709551616"), json(18446744073709551616.0));
  EXPECT_EQ(parse_json_text("\xef\xbb\xbf{}"), json::object());
  EXPECT_THROW(parse_json_text("{} x"), SceneError);
}

TEST(SceneDocumentTest, NanIsRejected) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/camera/eye/2", nan), "/camera/eye/2",
                       {"must be a finite number", "nan"}));
}

TEST(SceneDocumentTest, ReadJsonFile) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("tessera_scene_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto good = dir / "good.json";
  const auto bad = dir / "bad.json";
  std::ofstream(good) << minimal_scene().dump();
  std::ofstream(bad) << "{\"image\": [1, 2,]}";

  EXPECT_EQ(read_json_file(good), minimal_scene());
  EXPECT_THROW(read_json_file(dir / "missing.json"), std::runtime_error);
  EXPECT_THROW(read_json_file(dir), std::runtime_error);
  try {
    read_json_file(bad);
    FAIL() << "expected a syntax error";
  } catch (const SceneError& error) {
    EXPECT_NE(error.detail().find("line 1, column 17"), std::string::npos) << error.what();
  }
  // A file without a size, such as a pipe, is read to its end.
  const auto pipe = dir / "pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
  std::thread writer([&] { std::ofstream(pipe) << minimal_scene().dump(); });
  EXPECT_EQ(read_json_file(pipe), minimal_scene());
  writer.join();
  std::filesystem::remove_all(dir);
}

TEST(SceneDocumentTest, Version) {
  EXPECT_NO_THROW(parse_scene(with(minimal_scene(), "/version", 1)));
  EXPECT_NO_THROW(parse_scene(with(minimal_scene(), "/version", 1.0)));
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/version", 2), "/version", {"must be 1", "got 2"}));
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/version", "1"), "/version",
                       {"must be an integer, got string"}));
  // The version decides which keys exist, so it is judged before them.
  EXPECT_TRUE(fails_at(with(with(minimal_scene(), "/version", 2), "/new_key", 1), "/version", {}));
}

TEST(SceneDocumentTest, UnknownTopLevelKey) {
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/backgruond", 0), "/backgruond",
                       {"unknown key \"backgruond\"", "did you mean \"background\"?"}));
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/zzz", 0), "/zzz",
                       {"unknown key \"zzz\"", "known keys here:", "\"objects\""}));
}

TEST(SceneDocumentTest, PointerEscapesUnknownKeys) {
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/a~1b~0c", 0), "/a~1b~0c", {"unknown key"}));
}

// --- image ---

TEST(SceneImageTest, Required) {
  json scene = minimal_scene();
  scene.erase("image");
  EXPECT_TRUE(fails_at(scene, "/image", {"required"}));
  scene = minimal_scene();
  scene["image"].erase("height");
  EXPECT_TRUE(fails_at(scene, "/image/height", {"required"}));
  EXPECT_TRUE(
      fails_at(with(minimal_scene(), "/image", 640), "/image", {"must be an object, got number"}));
}

TEST(SceneImageTest, SizeRules) {
  const json scene = minimal_scene();
  EXPECT_TRUE(fails_at(with(scene, "/image/width", 0), "/image/width", {"must be >= 1, got 0"}));
  EXPECT_TRUE(fails_at(with(scene, "/image/width", 20000), "/image/width",
                       {"must be <= 16384 (limit max_width), got 20000"}));
  EXPECT_TRUE(fails_at(with(scene, "/image/height", 5.5), "/image/height",
                       {"must be an integer, got 5.5"}));
  EXPECT_TRUE(fails_at(with(scene, "/image/height", "3"), "/image/height",
                       {"must be an integer, got string"}));
  EXPECT_TRUE(fails_at(with(scene, "/image/width", std::numeric_limits<std::uint64_t>::max()),
                       "/image/width", {"limit max_width"}));
  Limits limits;
  limits.max_height = 2;
  EXPECT_TRUE(fails_at(scene, "/image/height", {"must be <= 2 (limit max_height), got 3"}, limits));
  EXPECT_EQ(parse_scene(with(scene, "/image/width", 7.0)).width, 7);
}

// --- camera ---

TEST(SceneCameraTest, RequiredParts) {
  json scene = minimal_scene();
  scene.erase("camera");
  EXPECT_TRUE(fails_at(scene, "/camera", {"required"}));
  scene = minimal_scene();
  scene["camera"].erase("eye");
  EXPECT_TRUE(fails_at(scene, "/camera/eye", {"required"}));
  scene = minimal_scene();
  scene["camera"].erase("look_at");
  EXPECT_TRUE(fails_at(scene, "/camera/look_at", {"required"}));
}

TEST(SceneCameraTest, VectorRules) {
  const json scene = minimal_scene();
  EXPECT_TRUE(fails_at(with(scene, "/camera/eye", {0, 1}), "/camera/eye",
                       {"must be an array of 3 numbers, got an array of 2 elements"}));
  EXPECT_TRUE(fails_at(with(scene, "/camera/eye", "origin"), "/camera/eye",
                       {"must be an array of 3 numbers, got string"}));
  EXPECT_TRUE(fails_at(with(scene, "/camera/eye/1", "1"), "/camera/eye/1",
                       {"must be a number, got string"}));
  EXPECT_TRUE(fails_at(with(scene, "/camera/eye/1", nullptr), "/camera/eye/1",
                       {"must be a number, got null"}));
}

TEST(SceneCameraTest, FieldOfView) {
  const json scene = minimal_scene();
  EXPECT_TRUE(
      fails_at(with(scene, "/camera/fov_y", 0), "/camera/fov_y", {"must be in (0, 180), got 0"}));
  EXPECT_TRUE(fails_at(with(scene, "/camera/fov_y", 180), "/camera/fov_y",
                       {"must be in (0, 180), got 180"}));
  EXPECT_DOUBLE_EQ(parse_scene(with(scene, "/camera/fov_y", 179.5)).camera.fov_y_degrees, 179.5);
}

TEST(SceneCameraTest, Geometry) {
  const json scene = minimal_scene();
  EXPECT_TRUE(fails_at(with(scene, "/camera/look_at", {0, 0, 5}), "/camera/look_at",
                       {"must differ from \"eye\""}));
  EXPECT_TRUE(fails_at(with(scene, "/camera/up", {0, 0, 0}), "/camera/up", {"non-zero"}));
  EXPECT_TRUE(fails_at(with(scene, "/camera/up", {0, 0, 2}), "/camera/up", {"parallel"}));
  // Looking straight down with the default up is the usual way to hit this.
  EXPECT_TRUE(fails_at(with(scene, "/camera/eye", {0, 5, 0}), "/camera/up", {"parallel"}));
  EXPECT_TRUE(fails_at(with(scene, "/camera/lookat", {0, 0, 0}), "/camera/lookat",
                       {"unknown key", "did you mean \"look_at\"?"}));
}

// --- render settings ---

TEST(SceneRenderTest, Rules) {
  const json scene = minimal_scene();
  EXPECT_TRUE(
      fails_at(with(scene, "/render", json::array()), "/render", {"must be an object, got array"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/samples_per_pixel", 0), "/render/samples_per_pixel",
                       {"must be >= 1, got 0"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/samples_per_pixel", 4097), "/render/samples_per_pixel",
                       {"must be <= 4096 (limit max_samples_per_pixel), got 4097"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/max_depth", -1), "/render/max_depth",
                       {"must be >= 0, got -1"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/max_depth", 65), "/render/max_depth",
                       {"must be <= 64 (limit max_depth), got 65"}));
  EXPECT_TRUE(
      fails_at(with(scene, "/render/tile_size", 0), "/render/tile_size", {"must be >= 1, got 0"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/tile_size", 4097), "/render/tile_size",
                       {"must be <= 4096 (limit max_tile_size), got 4097"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/tile_size", 2.5), "/render/tile_size",
                       {"must be an integer, got 2.5"}));
  EXPECT_TRUE(
      fails_at(with(scene, "/render/output_transfer", "sRGB"), "/render/output_transfer",
               {"must be one of \"srgb\", \"linear\", got \"sRGB\"", "did you mean \"srgb\"?"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/output_transfer", 1), "/render/output_transfer",
                       {"must be a string", "got number"}));
  EXPECT_TRUE(fails_at(with(scene, "/render/samples", 4), "/render/samples",
                       {"unknown key", "\"samples_per_pixel\""}));
}

TEST(SceneRenderTest, Values) {
  json scene = minimal_scene();
  scene["render"] = {
      {"samples_per_pixel", 16}, {"max_depth", 0}, {"tile_size", 8}, {"output_transfer", "linear"}};
  const RenderSettings render = parse_scene(scene).render;
  EXPECT_EQ(render.samples_per_pixel, 16);
  EXPECT_EQ(render.max_depth, 0);
  EXPECT_EQ(render.tile_size, 8);
  EXPECT_EQ(render.output_transfer, OutputTransfer::linear);
}

// --- colors ---

TEST(SceneColorsTest, Rules) {
  const json scene = minimal_scene();
  EXPECT_EQ(parse_scene(with(scene, "/background", 0.5)).background, Color(0.5));
  EXPECT_EQ(parse_scene(with(scene, "/ambient_light", {0.1, 0.2, 0.3})).ambient_light,
            Color(0.1, 0.2, 0.3));
  EXPECT_TRUE(fails_at(with(scene, "/background", {0, -0.5, 0}), "/background/1",
                       {"must be >= 0, got -0.5"}));
  EXPECT_TRUE(
      fails_at(with(scene, "/ambient_light", -1), "/ambient_light", {"must be >= 0, got -1"}));
  EXPECT_TRUE(fails_at(with(scene, "/background", "black"), "/background",
                       {"must be a color", "got string"}));
  EXPECT_TRUE(fails_at(with(scene, "/background", {0, 0, 0, 1}), "/background",
                       {"must be a color", "got an array of 4 elements"}));
}

// --- a whole scene ---

TEST(SceneValidTest, MinimalSceneGetsDefaults) {
  const Scene scene = parse_scene(minimal_scene());
  EXPECT_EQ(scene.width, 4);
  EXPECT_EQ(scene.height, 3);
  EXPECT_EQ(scene.camera.up, Vec3(0, 1, 0));
  EXPECT_EQ(scene.camera.fov_y_degrees, 45.0);
  EXPECT_EQ(scene.render.samples_per_pixel, 1);
  EXPECT_EQ(scene.render.max_depth, 5);
  EXPECT_EQ(scene.render.tile_size, 32);
  EXPECT_EQ(scene.render.output_transfer, OutputTransfer::srgb);
  EXPECT_EQ(scene.background, Color(0.0));
  EXPECT_EQ(scene.ambient_light, Color(0.1));
  ASSERT_EQ(scene.materials.size(), 1u);
  const Material& m = scene.materials[0];
  EXPECT_EQ(m.emission, Color(0.0));
  EXPECT_EQ(m.ambient, Color(0.2));
  EXPECT_EQ(m.diffuse, Color(0.8));
  EXPECT_EQ(m.specular, Color(0.0));
  EXPECT_EQ(m.shininess, 0.0);
  EXPECT_EQ(m.reflection, Color(0.0));
  EXPECT_EQ(m.transmission, Color(0.0));
  EXPECT_EQ(m.ior, 1.0);
  EXPECT_FALSE(m.checker.has_value());
  EXPECT_TRUE(scene.lights.empty());
  EXPECT_TRUE(scene.objects.empty());
}

TEST(SceneValidTest, CompleteScene) {
  const Scene scene = parse_scene_text(R"({
    "version": 1,
    "image": {"width": 640, "height": 480},
    "camera": {"eye": [0, 1, 6], "look_at": [0, 0, 0], "up": [0, 2, 0], "fov_y": 60},
    "render": {"samples_per_pixel": 4, "max_depth": 8, "tile_size": 16,
               "output_transfer": "linear"},
    "background": [0.1, 0.2, 0.3],
    "ambient_light": 0.05,
    "materials": {
      "glass": {"specular": 0.9, "shininess": 200, "transmission": 0.8, "ior": 1.5,
                "diffuse": 0.05},
      "floor": {"checker": {"size": 0.5, "diffuse": [0.1, 0.1, 0.1]}}
    },
    "lights": [
      {"type": "point", "position": [2, 5, 2], "intensity": [1, 0.9, 0.8],
       "attenuation": [1, 0.1, 0.01]},
      {"type": "directional", "direction": [0, -1, -1]},
      {"type": "spot", "position": [0, 5, 0], "direction": [0, -1, 0], "cutoff": 30,
       "exponent": 8}
    ],
    "objects": [
      {"type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "glass"},
      {"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": "floor"},
      {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1],
       "material": {"diffuse": [0.8, 0.1, 0.1]},
       "transform": [{"scale": 0.5}, {"translate": [3, 0.5, 0]}]},
      {"type": "triangle", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]},
      {"type": "mesh", "positions": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
       "triangles": [[0, 1, 2], [0, 2, 3]], "thin": true}
    ]
  })");
  EXPECT_EQ(scene.width, 640);
  EXPECT_EQ(scene.height, 480);
  EXPECT_EQ(scene.camera.eye, Vec3(0, 1, 6));
  EXPECT_EQ(scene.camera.up, Vec3(0, 1, 0));
  EXPECT_EQ(scene.camera.fov_y_degrees, 60.0);
  EXPECT_EQ(scene.render.samples_per_pixel, 4);
  EXPECT_EQ(scene.render.max_depth, 8);
  EXPECT_EQ(scene.render.tile_size, 16);
  EXPECT_EQ(scene.render.output_transfer, OutputTransfer::linear);
  EXPECT_EQ(scene.background, Color(0.1, 0.2, 0.3));
  EXPECT_EQ(scene.ambient_light, Color(0.05));

  // Default first, then named materials in key order, then the inline one.
  ASSERT_EQ(scene.materials.size(), 4u);
  const Material& floor = scene.materials[1];
  const Material& glass = scene.materials[2];
  ASSERT_TRUE(floor.checker.has_value());
  EXPECT_EQ(floor.checker->diffuse, Color(0.1));
  EXPECT_EQ(floor.checker->ambient, Color(0.2));
  EXPECT_EQ(glass.specular, Color(0.9));
  EXPECT_EQ(glass.reflection, Color(0.9));
  EXPECT_EQ(glass.shininess, 200.0);
  EXPECT_EQ(glass.transmission, Color(0.8));
  EXPECT_EQ(glass.ior, 1.5);
  EXPECT_EQ(scene.materials[3].diffuse, Color(0.8, 0.1, 0.1));

  ASSERT_EQ(scene.lights.size(), 3u);
  EXPECT_EQ(std::get<PointLight>(scene.lights[0]).attenuation.linear, 0.1);
  const auto& sun = std::get<DirectionalLight>(scene.lights[1]);
  EXPECT_NEAR(sun.direction.y, -std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(sun.direction.z, -std::sqrt(0.5), 1e-15);
  EXPECT_EQ(std::get<SpotLight>(scene.lights[2]).cutoff_degrees, 30.0);
  EXPECT_EQ(std::get<SpotLight>(scene.lights[2]).exponent, 8.0);

  ASSERT_EQ(scene.objects.size(), 5u);
  EXPECT_EQ(scene.objects[0].material, 2u);
  EXPECT_EQ(scene.objects[1].material, 1u);
  EXPECT_EQ(scene.objects[2].material, 3u);
  EXPECT_EQ(scene.objects[3].material, 0u);
  EXPECT_EQ(std::get<Sphere>(scene.objects[0].shape).radius, 1.0);
  EXPECT_EQ(std::get<Plane>(scene.objects[1].shape).normal, Vec3(0, 1, 0));
  EXPECT_EQ(scene.objects[0].transform, Mat4(1.0));
  EXPECT_EQ(scene.objects[2].transform * glm::dvec4(1, 1, 1, 1), glm::dvec4(3.5, 1, 0.5, 1));
  EXPECT_FALSE(std::get<Triangle>(scene.objects[3].shape).normals.has_value());
  const auto& mesh = std::get<Mesh>(scene.objects[4].shape);
  EXPECT_TRUE(mesh.thin);
  EXPECT_TRUE(mesh.normals.empty());
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
}

}  // namespace
}  // namespace tessera::scene_test

namespace tessera::scene_test {
namespace {

// The limit a scene breaks, as SceneError names it: "" when it breaks another rule.
std::pair<std::string, std::uint64_t> limit_broken(const json& document, const Limits& limits) {
  try {
    parse_scene(document, limits);
  } catch (const SceneError& error) {
    return {error.limit(), error.limit_value()};
  }
  return {"(none: it parsed)", 0};
}

TEST(SceneLimitsTest, EachLimitIsNamedWithItsValue) {
  Limits tight;
  tight.max_width = 100;
  tight.max_pixels = 30;
  tight.max_samples_per_pixel = 8;
  tight.max_depth = 2;
  tight.max_tile_size = 16;
  tight.max_objects = 1;
  tight.max_lights = 1;
  tight.max_materials = 1;
  tight.max_triangles = 1;
  const json scene = minimal_scene();  // 4x3
  using Broken = std::pair<std::string, std::uint64_t>;
  EXPECT_EQ(limit_broken(with(scene, "/image/width", 101), tight), (Broken{"max_width", 100}));
  EXPECT_EQ(limit_broken(with(scene, "/image/width", 11), tight), (Broken{"max_pixels", 30}));
  EXPECT_EQ(limit_broken(with(scene, "/render/samples_per_pixel", 9), tight),
            (Broken{"max_samples_per_pixel", 8}));
  EXPECT_EQ(limit_broken(with(scene, "/render/max_depth", 3), tight), (Broken{"max_depth", 2}));
  EXPECT_EQ(limit_broken(with(scene, "/render/tile_size", 17), tight),
            (Broken{"max_tile_size", 16}));
  EXPECT_EQ(limit_broken(with(scene, "/objects", json::array({sphere(), sphere()})), tight),
            (Broken{"max_objects", 1}));
  const json light = {{"type", "directional"}, {"direction", {0, -1, 0}}};
  EXPECT_EQ(limit_broken(with(scene, "/lights", json::array({light, light})), tight),
            (Broken{"max_lights", 1}));
  const json two_materials = {{"a", {{"diffuse", 0.5}}}, {"b", {{"diffuse", 0.5}}}};
  EXPECT_EQ(limit_broken(with(scene, "/materials", two_materials), tight),
            (Broken{"max_materials", 1}));
  const json box = {{"type", "box"}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}};
  EXPECT_EQ(limit_broken(with(scene, "/objects", json::array({box})), tight),
            (Broken{"max_triangles", 1}));
  // Other rules are not limits, even where a maximum is involved.
  EXPECT_EQ(limit_broken(with(scene, "/render/max_depth", -1), tight), (Broken{"", 0}));
  EXPECT_EQ(limit_broken(with(scene, "/image/width", "wide"), tight), (Broken{"", 0}));
  // Within every limit, it parses; with none at all, anything goes.
  EXPECT_EQ(limit_broken(scene, tight).first, "(none: it parsed)");
  EXPECT_EQ(limit_broken(with(scene, "/render/samples_per_pixel", 100000), Limits::none()).first,
            "(none: it parsed)");
}

}  // namespace
}  // namespace tessera::scene_test
