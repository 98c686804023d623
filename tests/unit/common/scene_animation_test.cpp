// Keyframe tracks: where they may stand, how they are checked, and the values they give
// (docs/scene-format.md, "Animation"), against values worked out by hand.
#include <cmath>
#include <filesystem>
#include <string>
#include <variant>

#include <gtest/gtest.h>

#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scene/frame_list.hpp"
#include "common/scene/scene_frames.hpp"
#include "scene_test_support.hpp"

namespace tessera::scene_test {
namespace {

json animated(json document, int first = 0, int last = 10) {
  document["animation"] = {{"frames", {first, last}}, {"fps", 24}};
  return document;
}

json track(json keys, const std::string& interpolation = "linear") {
  return {{"keys", std::move(keys)}, {"interpolation", interpolation}};
}

Scene at_frame(const json& document, int frame) {
  return parse_scene_frame(document, frame, Limits{});
}

// --- the "animation" member ---

TEST(SceneAnimationTest, StillSceneIsFrameZero) {
  const Scene scene = parse_scene(minimal_scene());
  EXPECT_FALSE(scene.animation.animated);
  EXPECT_EQ(scene.animation.first, 0);
  EXPECT_EQ(scene.animation.last, 0);
  EXPECT_EQ(scene.frame, 0);
  EXPECT_TRUE(scene.animation.tracks.empty());
}

TEST(SceneAnimationTest, RangeAndRate) {
  const Scene scene = parse_scene(animated(minimal_scene(), 1, 48));
  EXPECT_TRUE(scene.animation.animated);
  EXPECT_EQ(scene.animation.first, 1);
  EXPECT_EQ(scene.animation.last, 48);
  EXPECT_EQ(scene.animation.frame_count(), 48);
  EXPECT_EQ(scene.animation.fps, 24.0);
  EXPECT_EQ(scene.frame, 1);  // parse_scene() reads the first frame
}

TEST(SceneAnimationTest, RangeErrors) {
  const json base = minimal_scene();
  EXPECT_TRUE(fails_at(with(base, "/animation", 24), "/animation", {"must be an object"}));
  EXPECT_TRUE(
      fails_at(with(base, "/animation", json::object()), "/animation/frames", {"required"}));
  EXPECT_TRUE(fails_at(with(base, "/animation", {{"frames", {1}}}), "/animation/frames",
                       {"[first, last]"}));
  EXPECT_TRUE(fails_at(with(base, "/animation", {{"frames", {5, 1}}}), "/animation/frames/1",
                       {"must be at least the first frame (5), got 1"}));
  EXPECT_TRUE(fails_at(with(base, "/animation", {{"frames", {-1, 4}}}), "/animation/frames/0",
                       {"must be >= 0"}));
  EXPECT_TRUE(fails_at(with(base, "/animation", {{"frames", {1, 4}}, {"fps", 0}}), "/animation/fps",
                       {"must be in (0, 1000]"}));
  EXPECT_TRUE(fails_at(with(base, "/animation", {{"frames", {1, 4}}, {"rate", 24}}),
                       "/animation/rate", {"unknown key"}));
  Limits limits;
  limits.max_frames = 100;
  try {
    parse_scene(with(base, "/animation", {{"frames", {1, 101}}}), limits);
    FAIL() << "101 frames passed a limit of 100";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.pointer(), "/animation/frames");
    EXPECT_EQ(e.limit(), "max_frames");
  }
}

// --- where tracks stand, and their errors ---

TEST(SceneAnimationTest, TrackNeedsAnAnimation) {
  EXPECT_TRUE(fails_at(with(minimal_scene(), "/camera/eye", track({{0, {0, 0, 5}}})), "/camera/eye",
                       {"is a keyframe track, but the scene is not animated"}));
}

TEST(SceneAnimationTest, TrackStructureErrors) {
  const json base = animated(minimal_scene());
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", {{"keys", json::array()}}), "/camera/eye/keys",
                       {"must hold at least one key"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", {{"keys", 3}}), "/camera/eye/keys",
                       {"must be an array of keys"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", {{"keys", {{0, {0, 0, 5}}}}, {"ease", 1}}),
                       "/camera/eye/ease", {"unknown key"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", track({{0, {0, 0, 5}}}, "cubic")),
                       "/camera/eye/interpolation", {"\"linear\", \"smooth\", \"step\""}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", track({{0, {0, 0, 5}, 1}})), "/camera/eye/keys/0",
                       {"must be a key [frame, value]"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", track({{4, {0, 0, 5}}, {4, {0, 0, 6}}})),
                       "/camera/eye/keys/1/0",
                       {"must be after the frame of the key before it (4), got 4"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", track({{5, {0, 0, 5}}, {2, {0, 0, 6}}})),
                       "/camera/eye/keys/1/0", {"must be after"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", track({{11, {0, 0, 5}}})), "/camera/eye/keys/0/0",
                       {"must be <= 10", "frames are 0 to 10"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", track({{1.5, {0, 0, 5}}})), "/camera/eye/keys/0/0",
                       {"must be an integer"}));
}

TEST(SceneAnimationTest, KeysObeyTheFieldsOwnRules) {
  const json base = animated(minimal_scene());
  // Shape: a vector field takes [x, y, z] keys.
  EXPECT_TRUE(fails_at(with(base, "/camera/eye", track({{0, {0, 0, 5}}, {5, 5}})),
                       "/camera/eye/keys/1/1", {"must be an array of 3 numbers"}));
  // Range: a colour cannot go negative, a field of view stays in (0, 180).
  EXPECT_TRUE(fails_at(with(base, "/background", track({{0, 0.5}, {3, {0, -1, 0}}})),
                       "/background/keys/1/1/1", {"must be >= 0"}));
  EXPECT_TRUE(fails_at(with(base, "/camera/fov_y", track({{0, 40}, {3, 180}})),
                       "/camera/fov_y/keys/1/1", {"must be in (0, 180)"}));
  EXPECT_TRUE(fails_at(animated(with_light({{"type", "spot"},
                                            {"position", {0, 5, 0}},
                                            {"direction", {0, -1, 0}},
                                            {"cutoff", track({{0, 30}, {10, 95}})}})),
                       "/lights/0/cutoff/keys/1/1", {"must be in (0, 90]"}));
  // A direction must not be zero, even at a key.
  EXPECT_TRUE(fails_at(
      animated(with_light({{"type", "directional"}, {"direction", track({{0, {0, 0, 0}}})}})),
      "/lights/0/direction/keys/0/1", {"must be a non-zero vector"}));
}

TEST(SceneAnimationTest, OnlyAnimatableFieldsTakeTracks) {
  const json base = animated(minimal_scene());
  EXPECT_TRUE(fails_at(with(base, "/image/width", track({{0, 4}})), "/image/width",
                       {"must be an integer, got object"}));
  EXPECT_TRUE(fails_at(with(base, "/render", {{"max_depth", track({{0, 4}})}}), "/render/max_depth",
                       {"must be an integer, got object"}));
  EXPECT_TRUE(fails_at(
      animated(
          with_object({{"type", "sphere"}, {"center", track({{0, {0, 0, 0}}})}, {"radius", 1}})),
      "/objects/0/center", {"must be an array of 3 numbers, got object"}));
}

TEST(SceneAnimationTest, EveryFrameIsChecked) {
  // Valid at every key, but zero half-way: refused at submit, naming the frame.
  EXPECT_TRUE(
      fails_at(animated(with_light({{"type", "directional"},
                                    {"direction", track({{0, {1, 0, 0}}, {2, {-1, 0, 0}}})}})),
               "/lights/0/direction", {"at frame 1, must be a non-zero vector"}));
  // The camera flies through the point it looks at.
  EXPECT_TRUE(fails_at(
      with(animated(minimal_scene()), "/camera/eye", track({{0, {0, 0, 5}}, {10, {0, 0, -5}}})),
      "/camera/look_at", {"at frame 5, must differ from \"eye\""}));
  // A scale through zero squashes the object flat.
  EXPECT_TRUE(
      fails_at(animated(with_object({{"type", "sphere"},
                                     {"center", {0, 0, 0}},
                                     {"radius", 1},
                                     {"transform", {{{"scale", track({{0, 1}, {4, -1}})}}}}})),
               "/objects/0/transform/0/scale", {"at frame 2, must be non-zero"}));
}

TEST(SceneAnimationTest, TracksInAMeshFilesObject) {
  const FolderSceneFiles files(std::filesystem::path(TESSERA_SOURCE_DIR) / "examples");
  json document = animated(minimal_scene());
  document["objects"] = {{{"type", "mesh"},
                          {"file", "models/still_life.obj"},
                          {"transform", {{{"scale", track({{0, 1}, {10, 2}})}}}}}};
  const Scene scene = parse_scene_frame(document, 5, Limits{}, nullptr, &files);
  ASSERT_GT(scene.objects.size(), 1u);  // the file's parts, all placed by the frame's scale
  for (const Object& object : scene.objects) EXPECT_EQ(object.transform[0][0], 1.5);
  document["objects"][0]["transform"][0]["scale"] = track({{0, 1}, {10, -1}});
  try {
    parse_scene(document, Limits{}, nullptr, &files);
    FAIL() << "a scale through zero passed";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.pointer(), "/objects/0/transform/0/scale");
    EXPECT_NE(e.detail().find("at frame 5, must be non-zero"), std::string::npos) << e.detail();
  }
}

TEST(SceneAnimationTest, TrackLimit) {
  json document = animated(minimal_scene());
  document["camera"]["eye"] = track({{0, {0, 0, 5}}});
  document["camera"]["fov_y"] = track({{0, 40}});
  Limits limits;
  limits.max_tracks = 1;
  try {
    parse_scene(document, limits);
    FAIL() << "two tracks passed a limit of one";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.pointer(), "/camera/fov_y");
    EXPECT_EQ(e.limit(), "max_tracks");
  }
  limits.max_tracks = 2;
  EXPECT_EQ(parse_scene(document, limits).animation.tracks.size(), 2u);
}

TEST(SceneAnimationTest, FrameOutsideTheRange) {
  const json document = animated(minimal_scene(), 1, 10);
  try {
    at_frame(document, 11);
    FAIL() << "frame 11 of 1-10 was read";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.pointer(), "/animation/frames");
    EXPECT_NE(e.detail().find("has no frame 11"), std::string::npos) << e.detail();
  }
}

// --- the values, worked out by hand ---

double eye_x(const json& keys, const std::string& interpolation, int frame) {
  json document = animated(minimal_scene(), 0, 40);
  json x_keys = json::array();
  for (const auto& key : keys) x_keys.push_back({key[0], {key[1], 1, 5}});
  document["camera"]["eye"] = track(x_keys, interpolation);
  return at_frame(document, frame).camera.eye.x;
}

TEST(SceneAnimationTest, Linear) {
  const json keys = {{0, 0}, {10, 10}, {20, 30}};
  EXPECT_EQ(eye_x(keys, "linear", 0), 0.0);
  EXPECT_EQ(eye_x(keys, "linear", 3), 3.0);
  EXPECT_EQ(eye_x(keys, "linear", 10), 10.0);
  EXPECT_EQ(eye_x(keys, "linear", 15), 20.0);
  // Before the first key and after the last, the end keys hold.
  EXPECT_EQ(eye_x({{5, 2}, {10, 4}}, "linear", 0), 2.0);
  EXPECT_EQ(eye_x(keys, "linear", 40), 30.0);
}

TEST(SceneAnimationTest, Step) {
  const json keys = {{0, 1}, {5, 2}, {10, 3}};
  EXPECT_EQ(eye_x(keys, "step", 4), 1.0);
  EXPECT_EQ(eye_x(keys, "step", 5), 2.0);
  EXPECT_EQ(eye_x(keys, "step", 9), 2.0);
  EXPECT_EQ(eye_x(keys, "step", 30), 3.0);
}

TEST(SceneAnimationTest, SmoothIsCatmullRom) {
  // Interior segment 10..20: tangents (30 - 0) / 20 = 1.5 and (30 - 10) / 20 = 1 per frame.
  // At s = 1/2: h00 = h01 = 1/2, h10 = 1/8, h11 = -1/8, so
  // 10/2 + 10 * 1.5 / 8 + 30/2 - 10 * 1 / 8 = 5 + 1.875 + 15 - 1.25 = 20.625.
  const json keys = {{0, 0}, {10, 10}, {20, 30}, {30, 30}};
  EXPECT_NEAR(eye_x(keys, "smooth", 15), 20.625, 1e-12);
  // At the keys themselves, the keys' values exactly.
  EXPECT_EQ(eye_x(keys, "smooth", 10), 10.0);
  EXPECT_EQ(eye_x(keys, "smooth", 20), 30.0);
  // Clamped ends: a copy of the end key one segment out makes both tangents of a lone
  // segment 0..10 from 0 to 10 equal 10 / 20 = 0.5. At s = 0.2: h00 = 0.896, h10 = 0.128,
  // h01 = 0.104, h11 = -0.032, so 0.128 * 10 * 0.5 + 0.104 * 10 - 0.032 * 10 * 0.5 = 1.52.
  EXPECT_NEAR(eye_x({{0, 0}, {10, 10}}, "smooth", 2), 1.52, 1e-12);
  EXPECT_NEAR(eye_x({{0, 0}, {10, 10}}, "smooth", 5), 5.0, 1e-12);
}

TEST(SceneAnimationTest, SmoothStaysWithinBoundsOfBoundedFields) {
  // Keys 1, 0, 0, 1 at 0, 10, 20, 30: between 10 and 20 Catmull-Rom dips to
  // 10/8 * (-0.05) - 10/8 * 0.05 = -0.125 at 15. A position may go there; a colour stays
  // between its two keys, at 0.
  const json keys = {{0, 1}, {10, 0}, {20, 0}, {30, 1}};
  EXPECT_NEAR(eye_x(keys, "smooth", 15), -0.125, 1e-12);
  json document = animated(minimal_scene(), 0, 40);
  document["background"] = track(keys, "smooth");
  EXPECT_EQ(at_frame(document, 15).background, Color(0.0));
  EXPECT_GT(at_frame(document, 25).background.r, 0.0);
}

TEST(SceneAnimationTest, NumberKeysOfAColourStandForGrey) {
  json document = animated(minimal_scene(), 0, 10);
  document["ambient_light"] = track({{0, 0.2}, {10, {0.4, 0.6, 1.2}}});
  // The linear formula's own arithmetic, a + s * (b - a), at s = 1/2.
  EXPECT_EQ(at_frame(document, 5).ambient_light,
            Color(0.2 + 0.5 * (0.4 - 0.2), 0.2 + 0.5 * (0.6 - 0.2), 0.2 + 0.5 * (1.2 - 0.2)));
  EXPECT_EQ(at_frame(document, 0).ambient_light, Color(0.2));
}

TEST(SceneAnimationTest, EveryAnimatableField) {
  json document = animated(minimal_scene(), 0, 4);
  document["camera"] = {{"eye", track({{0, {0, 0, 5}}, {4, {4, 0, 5}}})},
                        {"look_at", track({{0, {0, 0, 0}}, {4, {0, 4, 0}}})},
                        {"up", track({{0, {0, 1, 0}}, {4, {1, 1, 0}}})},
                        {"fov_y", track({{0, 40}, {4, 60}})}};
  document["lights"] = {{{"type", "spot"},
                         {"position", track({{0, {0, 5, 0}}, {4, {4, 5, 0}}})},
                         {"direction", track({{0, {0, -1, 0}}, {4, {0, -1, 4}}})},
                         {"intensity", track({{0, 1}, {4, 2}})},
                         {"cutoff", track({{0, 30}, {4, 50}})},
                         {"exponent", track({{0, 1}, {4, 5}})}}};
  document["materials"] = {{"m",
                            {{"diffuse", track({{0, {1, 0, 0}}, {4, {0, 0, 1}}})},
                             {"shininess", track({{0, 10}, {4, 30}})},
                             {"ior", track({{0, 1}, {4, 2}})}}}};
  document["objects"] = {
      {{"type", "sphere"},
       {"center", {0, 0, 0}},
       {"radius", 1},
       {"material", {{"emission", track({{0, 0}, {4, 1}})}}},
       {"transform",
        {{{"translate", track({{0, {0, 0, 0}}, {4, {4, 0, 0}}})}},
         {{"rotate",
           {{"axis", track({{0, {0, 1, 0}}, {4, {1, 1, 0}}})},
            {"degrees", track({{0, 0}, {4, 90}})}}}},
         {{"scale", track({{0, 1}, {4, {2, 3, 4}}})}}}}},
      {{"type", "sphere"}, {"center", {3, 0, 0}}, {"radius", 1}, {"material", "m"}}};
  document["background"] = track({{0, 0}, {4, 1}});
  document["ambient_light"] = track({{0, 0}, {4, 0.4}});
  const Scene first = parse_scene(document);
  EXPECT_EQ(first.animation.tracks.size(), 19u);
  const Scene scene = at_frame(document, 1);
  EXPECT_EQ(scene.frame, 1);
  EXPECT_EQ(scene.camera.eye, Vec3(1, 0, 5));
  EXPECT_EQ(scene.camera.look_at, Vec3(0, 1, 0));
  EXPECT_EQ(scene.camera.up, glm::normalize(Vec3(0.25, 1, 0)));
  EXPECT_EQ(scene.camera.fov_y_degrees, 45.0);
  const auto& spot = std::get<SpotLight>(scene.lights[0]);
  EXPECT_EQ(spot.position, Vec3(1, 5, 0));
  EXPECT_EQ(spot.direction, glm::normalize(Vec3(0, -1, 1)));
  EXPECT_EQ(spot.intensity, Color(1.25));
  EXPECT_EQ(spot.cutoff_degrees, 35.0);
  EXPECT_EQ(spot.exponent, 2.0);
  EXPECT_EQ(scene.materials[1].diffuse, Color(0.75, 0, 0.25));
  EXPECT_EQ(scene.materials[1].shininess, 15.0);
  EXPECT_EQ(scene.materials[1].ior, 1.25);
  EXPECT_EQ(scene.materials[2].emission, Color(0.25));
  EXPECT_EQ(scene.background, Color(0.25));
  EXPECT_EQ(scene.ambient_light, Color(0.1));
  // The transform is the static one of the frame's values, composed by the same code.
  json still = json::array({{{"type", "sphere"},
                             {"center", {0, 0, 0}},
                             {"radius", 1},
                             {"transform",
                              {{{"translate", {1, 0, 0}}},
                               {{"rotate", {{"axis", {0.25, 1, 0}}, {"degrees", 22.5}}}},
                               {{"scale", {1.25, 1.5, 1.75}}}}}}});
  EXPECT_EQ(scene.objects[0].transform,
            parse_scene(with(minimal_scene(), "/objects", still)).objects[0].transform);
}

TEST(SceneAnimationTest, AdvancingEqualsReadingWhole) {
  json document = animated(minimal_scene(), 0, 6);
  document["camera"]["eye"] = track({{0, {0, 0, 5}}, {3, {1, 2, 5}}, {6, {0, 0, 6}}}, "smooth");
  document["lights"] = {{{"type", "point"},
                         {"position", track({{0, {0, 5, 0}}, {6, {4, 5, 0}}}, "step")},
                         {"intensity", track({{2, 1}, {4, {0.5, 0.2, 0.1}}})}}};
  document["materials"] = {{"b", {{"specular", track({{0, 0}, {6, 1}})}}},
                           {"a", {{"diffuse", 0.5}}}};
  document["objects"] = {
      {{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}, {"material", "b"}},
      {{"type", "sphere"}, {"center", {3, 0, 0}}, {"radius", 1}, {"material", {{"diffuse", 0.3}}}}};
  document["background"] = track({{0, 0}, {6, 1}});
  SceneFrames frames(document.dump(), Limits{});
  Scene scene = frames.take_first();
  for (int frame = 1; frame <= 6; ++frame) {
    scene = frames.at(frame, std::move(scene));
    const Scene whole = at_frame(document, frame);
    EXPECT_EQ(scene.frame, frame);
    EXPECT_EQ(scene.camera.eye, whole.camera.eye) << "frame " << frame;
    EXPECT_EQ(std::get<PointLight>(scene.lights[0]).position,
              std::get<PointLight>(whole.lights[0]).position);
    EXPECT_EQ(std::get<PointLight>(scene.lights[0]).intensity,
              std::get<PointLight>(whole.lights[0]).intensity);
    ASSERT_EQ(scene.materials.size(), whole.materials.size());
    for (std::size_t m = 0; m < scene.materials.size(); ++m) {
      EXPECT_EQ(scene.materials[m].specular, whole.materials[m].specular) << m;
      EXPECT_EQ(scene.materials[m].reflection, whole.materials[m].reflection) << m;
      EXPECT_EQ(scene.materials[m].diffuse, whole.materials[m].diffuse) << m;
    }
    EXPECT_EQ(scene.background, whole.background);
  }
}

// --- frame lists ---

TEST(FrameListTest, Forms) {
  EXPECT_EQ(parse_frame_list("7", 1, 48, 1000), (std::vector<int>{7}));
  EXPECT_EQ(parse_frame_list("1-5", 1, 48, 1000), (std::vector<int>{1, 2, 3, 4, 5}));
  EXPECT_EQ(parse_frame_list("1-10x3", 1, 48, 1000), (std::vector<int>{1, 4, 7, 10}));
  EXPECT_EQ(parse_frame_list("1-100x2", 1, 100, 1000).size(), 50u);
  EXPECT_EQ(parse_frame_list("10-12,1,5,11", 1, 48, 1000), (std::vector<int>{1, 5, 10, 11, 12}));
}

TEST(FrameListTest, Errors) {
  const auto error = [](std::string_view text) -> std::string {
    try {
      parse_frame_list(text, 1, 48, 100);
    } catch (const FrameListError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(error(""),
            "frame list \"\", at character 1: expected a frame, a range a-b or a-bxstep");
  EXPECT_EQ(error("0-5"),
            "frame list \"0-5\", at character 1: frame 0 is not one of the scene's, 1 to 48");
  EXPECT_EQ(error("1-49"),
            "frame list \"1-49\", at character 3: frame 49 is not one of the scene's, 1 to 48");
  EXPECT_EQ(error("5-1"),
            "frame list \"5-1\", at character 3: a range must not end before it starts (5-1)");
  EXPECT_EQ(error("1-5x0"), "frame list \"1-5x0\", at character 5: the step must be at least 1");
  EXPECT_EQ(error("1-5y2"),
            "frame list \"1-5y2\", at character 4: expected \",\" or the end of the list");
  EXPECT_EQ(error("1,,2"), "frame list \"1,,2\", at character 3: expected a frame number");
  EXPECT_EQ(error("1-"), "frame list \"1-\", at character 3: expected the range's last frame");
  EXPECT_EQ(error("99999999999"),
            "frame list \"99999999999\", at character 1: numbers are at most 9999999");
  EXPECT_NE(error("1-48,1-48,1-48").find("more than 100 frames"), std::string::npos);
}

TEST(FrameListTest, FormatReadsBack) {
  EXPECT_EQ(format_frame_list({1, 2, 3, 4, 5}), "1-5");
  EXPECT_EQ(format_frame_list({1, 3, 5, 7}), "1-7x2");
  EXPECT_EQ(format_frame_list({1, 2, 7}), "1,2,7");
  EXPECT_EQ(format_frame_list({1, 2, 3, 10, 20, 30, 31}), "1-3,10-30x10,31");
  for (const std::string text : {"1-5", "1-7x2", "1,2,7", "1-3,10-30x10,31"})
    EXPECT_EQ(format_frame_list(parse_frame_list(text, 0, 100, 100)), text);
}

}  // namespace
}  // namespace tessera::scene_test
