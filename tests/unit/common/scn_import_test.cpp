// tessera import: COS 426 .scn scenes, written from the format's published description,
// into our JSON scene format.
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/scene/scene_parser.hpp"
#include "tests/unit/common/scn_test_support.hpp"

namespace tessera::scn_test {
namespace {

constexpr double pi = std::numbers::pi;

void expect_near(const json& actual, const std::vector<double>& expected) {
  ASSERT_EQ(actual.size(), expected.size()) << actual.dump();
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_NEAR(actual[i].get<double>(), expected[i], 1e-12) << "element " << i << " of " << actual;
}

TEST_F(ScnImportTest, EachLightKindWithItsAttenuationAndSpotCone) {
  write("lights.scn", camera +
                          "dir_light 1 0.5 0.25  0 -1 0\n"
                          "point_light 0.5 0.5 0.5  1 2 3  1 0.1 0.01\n"
                          "spot_light 2 2 2  0 4 0  0 -1 0  0.5 0 0.2  0.5 3\n");
  const json scene = import("lights.scn");
  const json& lights = scene["lights"];
  ASSERT_EQ(lights.size(), 3u);
  EXPECT_EQ(lights[0], json::parse(R"({"type": "directional", "direction": [0, -1, 0],
                                       "intensity": [1, 0.5, 0.25]})"));
  EXPECT_EQ(lights[1], json::parse(R"({"type": "point", "position": [1, 2, 3],
                                       "intensity": [0.5, 0.5, 0.5],
                                       "attenuation": [1, 0.1, 0.01]})"));
  EXPECT_EQ(lights[2]["type"], "spot");
  EXPECT_EQ(lights[2]["position"], json::parse("[0, 4, 0]"));
  EXPECT_EQ(lights[2]["direction"], json::parse("[0, -1, 0]"));
  EXPECT_EQ(lights[2]["attenuation"], json::parse("[0.5, 0, 0.2]"));
  // sc is the cone's half-angle in radians; ours is in degrees.
  EXPECT_NEAR(lights[2]["cutoff"].get<double>(), 0.5 * 180 / pi, 1e-12);
  EXPECT_EQ(lights[2]["exponent"], 3.0);
}

TEST_F(ScnImportTest, CameraTakesHalfTheHorizontalAngleInRadians) {
  write("camera.scn", "camera 1 2 3  0 0 -2  0 3 0  0.6  0.01 100\n");
  const json camera = import("camera.scn")["camera"];
  EXPECT_EQ(camera["eye"], json::parse("[1, 2, 3]"));
  expect_near(camera["look_at"], {1, 2, 2});  // eye + towards, made unit
  EXPECT_EQ(camera["up"], json::parse("[0, 3, 0]"));
  // Vertical half-angle atan(tan(xfov) * height / width), doubled, in degrees.
  EXPECT_NEAR(camera["fov_y"].get<double>(), 2 * std::atan(std::tan(0.6) * 480 / 640) * 180 / pi,
              1e-12);

  ScnImportOptions square;
  square.width = 300;
  square.height = 300;
  const json scene = import("camera.scn", square);
  EXPECT_NEAR(scene["camera"]["fov_y"].get<double>(), 2 * 0.6 * 180 / pi, 1e-12);
  EXPECT_EQ(scene["image"], json::parse(R"({"width": 300, "height": 300})"));
}

TEST_F(ScnImportTest, MaterialsByIndexFromZeroAndMinusOneForTheDefault) {
  write("materials.scn", camera +
                             "material 0.1 0.2 0.3  0.4 0.5 0.6  0.7 0.8 0.9  0.1 0.1 0.1  "
                             "1 1 0  30 1.5 0\n"
                             "material 0 0 0  1 1 1  0 0 0  0 0 0  0 0 0  0 1\n"  // no texture
                             "sphere 1  0 0 0  1\n"
                             "sphere 0  2 0 0  1\n"
                             "sphere -1  4 0 0  1\n");
  const json scene = import("materials.scn");
  EXPECT_EQ(scene["materials"]["m0"], json::parse(R"({
      "ambient": [0.1, 0.2, 0.3], "diffuse": [0.4, 0.5, 0.6], "specular": [0.7, 0.8, 0.9],
      "transmission": [0.1, 0.1, 0.1], "emission": [1, 1, 0], "shininess": 30, "ior": 1.5})"));
  EXPECT_EQ(scene["objects"][0]["material"], "m1");
  EXPECT_EQ(scene["objects"][1]["material"], "m0");
  // The course reader's default material: ka 0.2, kd 0.5, ks 0.5, n 10.
  EXPECT_EQ(scene["objects"][2]["material"], "scn default");
  const Scene parsed = parse_scene(scene);
  const Material& fallback = parsed.materials[parsed.objects[2].material];
  EXPECT_EQ(fallback.diffuse, Color(0.5));
  EXPECT_EQ(fallback.specular, Color(0.5));
  EXPECT_EQ(fallback.reflection, Color(0.5));  // reflection is ks, as in the course
  EXPECT_EQ(fallback.shininess, 10.0);
}

TEST_F(ScnImportTest, NestedBeginBlocksComposeOuterTimesInner) {
  write("nested.scn", camera +
                          "material 0 0 0  1 0 0  0 0 0  0 0 0  0 0 0  1 1 0\n"
                          "begin 0\n"  // translate by (1, 2, 3)
                          "  1 0 0 1  0 1 0 2  0 0 1 3  0 0 0 1\n"
                          "  begin -1\n"  // scale by 2, then rotate 90 about z
                          "    0 -2 0 0  2 0 0 0  0 0 2 0  0 0 0 1\n"
                          "    sphere -1  1 0 0  0.5\n"
                          "  end\n"
                          "  box -1  0 0 0  1 1 1\n"
                          "end\n"
                          "sphere -1  0 0 0  1\n");
  const json objects = import("nested.scn")["objects"];
  ASSERT_EQ(objects.size(), 3u);
  // outer x inner: the point (1, 0, 0) goes to (0, 2, 0) by the inner matrix, then (1, 4, 3).
  expect_near(objects[0]["transform"][0]["matrix"],
              {0, -2, 0, 1, 2, 0, 0, 2, 0, 0, 2, 3, 0, 0, 0, 1});
  expect_near(objects[1]["transform"][0]["matrix"],
              {1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1});
  EXPECT_FALSE(objects[2].contains("transform"));
  // -1 inside a block is the block's material, also in a block inside it; outside, the
  // default.
  EXPECT_EQ(objects[0]["material"], "m0");
  EXPECT_EQ(objects[1]["material"], "m0");
  EXPECT_EQ(objects[2]["material"], "scn default");

  const Scene scene = parse_scene(import("nested.scn"));
  const Vec3 moved = Vec3(scene.objects[0].transform * glm::dvec4(1, 0, 0, 1));
  EXPECT_NEAR(moved.x, 1, 1e-12);
  EXPECT_NEAR(moved.y, 4, 1e-12);
  EXPECT_NEAR(moved.z, 3, 1e-12);
}

TEST_F(ScnImportTest, CylinderConeAndTriangleInOurSyntax) {
  write("shapes.scn", camera +
                          "cylinder -1  1 2 3  0.5 4\n"
                          "cone -1  0 1 0  1 2\n"
                          "tri -1  0 0 0  1 0 0  0 1 0\n"
                          "box -1  -1 -2 -3  1 2 3\n");
  const json objects = import("shapes.scn")["objects"];
  EXPECT_EQ(objects[0], json::parse(R"({"type": "cylinder", "center": [1, 2, 3], "radius": 0.5,
                                        "height": 4, "material": "scn default"})"));
  EXPECT_EQ(objects[1], json::parse(R"({"type": "cone", "center": [0, 1, 0], "radius": 1,
                                        "height": 2, "material": "scn default"})"));
  EXPECT_EQ(objects[2]["vertices"], json::parse("[[0, 0, 0], [1, 0, 0], [0, 1, 0]]"));
  EXPECT_EQ(objects[3]["min"], json::parse("[-1, -2, -3]"));
  EXPECT_EQ(objects[3]["max"], json::parse("[1, 2, 3]"));
}

TEST_F(ScnImportTest, MeshFileNamedFromWhereTheJsonGoes) {
  write("meshes/bunny.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  write("scenes/bunny.scn", camera + "mesh -1 ../meshes/bunny.off\n");
  write("scenes/parts/part.scn", "mesh -1 ../../meshes/bunny.off\n");
  write("scenes/both.scn", camera + "include parts/part.scn\n");

  ScnImportOptions options;
  options.output_dir = dir_ / "out";
  EXPECT_EQ(import("scenes/bunny.scn", options)["objects"][0],
            json::parse(R"({"type": "mesh", "file": "../meshes/bunny.off",
                            "material": "scn default"})"));
  options.output_dir = dir_ / "scenes" / "deeper" / "still";
  EXPECT_EQ(import("scenes/bunny.scn", options)["objects"][0]["file"], "../../../meshes/bunny.off");
  // Named in an included file, relative to that file.
  options.output_dir = dir_;
  EXPECT_EQ(import("scenes/both.scn", options)["objects"][0]["file"], "meshes/bunny.off");
  // No output folder: relative to the first .scn's.
  EXPECT_EQ(import("scenes/both.scn")["objects"][0]["file"], "../meshes/bunny.off");
  // An absolute name stays as it is.
  const std::string absolute = (dir_ / "meshes" / "bunny.off").generic_string();
  write("scenes/absolute.scn", camera + "mesh -1 " + absolute + "\n");
  EXPECT_EQ(import("scenes/absolute.scn", options)["objects"][0]["file"], absolute);
}

TEST_F(ScnImportTest, IncludeIsRelativeToTheIncludingFileAndInsideItsBlock) {
  write("parts/ball.scn",
        "material 0 0 0  0 0 1  0 0 0  0 0 0  0 0 0  1 1 0\n"  // this file's material 0
        "sphere 0  0 0 0  1\n"
        "sphere -1  0 0 0  1\n");
  write("main.scn", camera +
                        "material 0 0 0  1 0 0  0 0 0  0 0 0  0 0 0  1 1 0\n"
                        "begin 0  1 0 0 5  0 1 0 0  0 0 1 0  0 0 0 1\n"
                        "  include parts/ball.scn\n"
                        "end\n"
                        "sphere 0  0 0 0  1\n");
  const json scene = import("main.scn");
  const json& objects = scene["objects"];
  ASSERT_EQ(objects.size(), 3u);
  // Material indices count from 0 in each file, as the course's reader had them.
  EXPECT_EQ(scene["materials"]["m1"]["diffuse"], json::parse("[0, 0, 1]"));
  EXPECT_EQ(objects[0]["material"], "m1");
  // An included file starts at the default material, as the reader's did...
  EXPECT_EQ(objects[1]["material"], "scn default");
  // ...but inside the including block's transform.
  expect_near(objects[0]["transform"][0]["matrix"],
              {1, 0, 0, 5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
  EXPECT_EQ(objects[2]["material"], "m0");
}

TEST_F(ScnImportTest, CommentsAndCommandsAcrossLines) {
  write("layout.scn", "# a comment line\n" + camera +
                          "sphere -1   # material\n"
                          "  0 0 0     # centre\n"
                          "  2         # radius\n"
                          "ambient 0.2 0.2 0.2#no space before it\n"
                          "background +0.5 .25 1e-1\n");
  const json scene = import("layout.scn");
  EXPECT_EQ(scene["objects"][0]["radius"], 2.0);
  EXPECT_EQ(scene["ambient_light"], json::parse("[0.2, 0.2, 0.2]"));
  EXPECT_EQ(scene["background"], json::parse("[0.5, 0.25, 0.1]"));
}

TEST_F(ScnImportTest, ASceneWithoutLightsGetsTheReadersTwoAndAWarning) {
  write("dark.scn", camera + "sphere -1 0 0 0 1\n");
  std::vector<std::string> warnings;
  ScnImportOptions options;
  options.warn = [&](const std::string& warning) { warnings.push_back(warning); };
  const json scene = import("dark.scn", options);
  ASSERT_EQ(scene["lights"].size(), 2u);
  EXPECT_EQ(scene["lights"][0]["direction"], json::parse("[-3, -4, -5]"));
  EXPECT_EQ(scene["lights"][1]["intensity"], 0.5);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("no lights"), std::string::npos) << warnings[0];
  // The course's ambient light and background default to black.
  EXPECT_EQ(scene["ambient_light"], json::parse("[0, 0, 0]"));
}

TEST_F(ScnImportTest, AWholeSceneWithoutNewShapesPassesParseScene) {
  write("whole.scn",
        "camera 0 2 8  0 -0.2 -1  0 1 0  0.4  0.01 100\n"
        "ambient 0.1 0.1 0.1\n"
        "background 0.05 0.05 0.1\n"
        "material 0.2 0.2 0.2  0.8 0.2 0.2  0.5 0.5 0.5  0 0 0  0 0 0  40 1 0\n"
        "material 0 0 0  0.05 0.05 0.05  0.9 0.9 0.9  0.9 0.9 0.9  0 0 0  200 1.5 0\n"
        "dir_light 0.5 0.5 0.5  -1 -2 -1\n"
        "point_light 1 1 1  3 5 4  1 0 0.01\n"
        "spot_light 1 1 1  0 4 0  0 -1 0  1 0 0  0.4 4\n"
        "box 0  -5 -1 -5  5 0 5\n"
        "begin 1  1 0 0 0  0 1 0 1  0 0 1 0  0 0 0 1\n"
        "  sphere -1  0 0 0  1\n"
        "  tri 0  2 0 0  3 0 0  2.5 1 0\n"
        "end\n");
  const Scene scene = parse_scene(import("whole.scn"));
  EXPECT_EQ(scene.width, 640);
  EXPECT_EQ(scene.objects.size(), 3u);
  EXPECT_EQ(scene.lights.size(), 3u);
  EXPECT_EQ(scene.materials.size(), 3u);  // ours, and m0 and m1
  EXPECT_NEAR(std::get<SpotLight>(scene.lights[2]).cutoff_degrees, 0.4 * 180 / pi, 1e-12);
  EXPECT_NEAR(scene.objects[1].transform[3][1], 1.0, 1e-12);
  EXPECT_EQ(scene.materials[scene.objects[1].material].ior, 1.5);
}

}  // namespace
}  // namespace tessera::scn_test
