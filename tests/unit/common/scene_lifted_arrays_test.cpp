// parse_scene_text() lifts a mesh's big arrays out of the document: the Scene and every error
// must be those of the ordinary path, parse_scene() of the whole document.
#include <string>
#include <variant>

#include <gtest/gtest.h>

#include "scene_test_support.hpp"

namespace tessera::scene_test {
namespace {

// A grid of side × side positions on a slight bowl, two triangles per cell, with normals:
// every array well over the size that is lifted. Some coordinates are JSON integers.
json grid_mesh(int side) {
  json positions = json::array();
  json normals = json::array();
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      positions.push_back({x, 0.01 * (x * x + y * y) + 0.1, -y});
      normals.push_back({0.02 * x, 1, 0.5});
    }
  json triangles = json::array();
  for (int y = 0; y + 1 < side; ++y)
    for (int x = 0; x + 1 < side; ++x) {
      const int i = y * side + x;
      triangles.push_back({i, i + 1, i + side + 1});
      triangles.push_back({i, i + side + 1, i + side});
    }
  return {{"type", "mesh"},
          {"positions", positions},
          {"triangles", triangles},
          {"normals", normals},
          {"material", "default"}};
}

json grid_scene() {
  json scene = with_object(grid_mesh(20));
  scene["materials"] = {{"default", {{"diffuse", 0.5}}}};
  return scene;
}

const Mesh& mesh_of(const Scene& scene) { return std::get<Mesh>(scene.objects[0].shape); }

// The error of each path, or "" when it parses.
std::string error_of(const std::function<Scene()>& parse) {
  try {
    parse();
  } catch (const SceneError& error) {
    return error.pointer() + ": " + error.detail();
  }
  return "";
}

TEST(SceneLiftedArraysTest, TheMeshArraysAreLiftedAndGiveTheOrdinaryScene) {
  const std::string text = grid_scene().dump();
  const auto lifted = parse_json_fast_lifted(text, 64, 64);
  ASSERT_TRUE(lifted.has_value());
  EXPECT_EQ(lifted->lifted.size(), 3u);
  EXPECT_EQ(lifted->lifted.at("/objects/0/triangles").indices.size(), 3u * 2 * 19 * 19);
  EXPECT_TRUE(lifted->document["objects"][0]["positions"].empty());

  const Scene fast = parse_scene_text(text);
  const Scene ordinary = parse_scene(json::parse(text));
  EXPECT_EQ(mesh_of(fast).positions, mesh_of(ordinary).positions);
  EXPECT_EQ(mesh_of(fast).triangles, mesh_of(ordinary).triangles);
  EXPECT_EQ(mesh_of(fast).normals, mesh_of(ordinary).normals);
  ASSERT_EQ(mesh_of(fast).triangles.size(), 2u * 19 * 19);
  EXPECT_EQ(fast.materials.size(), ordinary.materials.size());

  // The edit applies to the document either way.
  const Scene edited =
      parse_scene_text(text, {}, [](json& document) { document["image"]["width"] = 7; });
  EXPECT_EQ(edited.width, 7);
}

TEST(SceneLiftedArraysTest, ABrokenRuleInALiftedArrayGetsTheOrdinaryError) {
  const json scene = grid_scene();
  const json variants[] = {
      with(scene, "/objects/0/triangles/300/1", 400),               // out of range
      with(scene, "/objects/0/triangles/301", {5, 6, 5}),           // degenerate
      with(scene, "/objects/0/normals/200", {0, 0, 0}),             // zero
      with(scene, "/objects/0/positions/100", {1, 2}),              // not lifted: two numbers
      with(scene, "/objects/0/triangles/17/2", 5.0),                // not lifted, and accepted
      with(scene, "/objects/0/triangles/18/0", -1),                 // not lifted: negative
      with(scene, "/objects/0/normals", json::array({{0, 0, 1}})),  // too few (small)
      with(with(scene, "/objects/0/positions", json::array({{0, 0, 0}, {1, 0, 0}})),
           "/objects/0/triangles", json::array()),  // positions' error comes first
  };
  for (const json& variant : variants) {
    const std::string text = variant.dump();
    const std::string fast = error_of([&] { return parse_scene_text(text); });
    const std::string ordinary = error_of([&] { return parse_scene(json::parse(text)); });
    EXPECT_EQ(fast, ordinary);
  }
  // Each variant above that breaks a rule was seen to: the comparison is not of two passes.
  EXPECT_NE(error_of([&] { return parse_scene_text(variants[0].dump()); }), "");
  EXPECT_NE(error_of([&] { return parse_scene_text(variants[1].dump()); }), "");
  EXPECT_NE(error_of([&] { return parse_scene_text(variants[2].dump()); }), "");
  EXPECT_EQ(error_of([&] { return parse_scene_text(variants[4].dump()); }), "");
}

TEST(SceneLiftedArraysTest, OnlyMeshesArraysAreLifted) {
  // A sphere with a misplaced "positions" key keeps it in the document, for the error.
  json scene = grid_scene();
  scene["objects"][0]["type"] = "sphere";
  const std::string text = scene.dump();
  EXPECT_TRUE(parse_json_fast_lifted(text, 64, 64)->lifted.empty());
  EXPECT_EQ(error_of([&] { return parse_scene_text(text); }),
            error_of([&] { return parse_scene(json::parse(text)); }));
  // Repeated keys: the last one is the one read, lifted or not.
  const std::string repeated =
      "{\"objects\": [{\"type\": \"mesh\", \"positions\": " + grid_mesh(20)["positions"].dump() +
      ", \"positions\": [[0,0,0],[1,0,0],[0,1,0]]}]}";
  const auto lifted = parse_json_fast_lifted(repeated, 64, 64);
  ASSERT_TRUE(lifted.has_value());
  EXPECT_TRUE(lifted->lifted.empty());
  EXPECT_EQ(lifted->document["objects"][0]["positions"].size(), 3u);
}

}  // namespace
}  // namespace tessera::scene_test
