// Frame n of an animated scene renders bit for bit as the still scene that holds each
// track's value at n, for every kind of track; and a frame whose objects did not move
// reuses the geometry built for the frame before.
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scene_frames.hpp"
#include "tests/unit/worker/render_helpers.hpp"

namespace tessera {
namespace {

using test::json;

// One animated field: its value at the two keys, frames 1 and 9.
struct Animated {
  std::string pointer;
  json from;
  json to;
};

constexpr int first_key = 1, last_key = 9, shown = 4;

// a + s (b - a), component by component: docs/scene-format.md's linear interpolation. A
// number beside a triple (a grey colour, a uniform scale) stands for three equal ones.
json lerp(const json& a, const json& b, double s) {
  if (a.is_number() && b.is_number())
    return a.get<double>() + s * (b.get<double>() - a.get<double>());
  const auto at = [](const json& v, std::size_t i) { return v.is_number() ? v : v[i]; };
  json out = json::array();
  for (std::size_t i = 0; i < 3; ++i) out.push_back(lerp(at(a, i), at(b, i), s));
  return out;
}

json animated_scene(const std::vector<Animated>& fields, json document = test::busy_scene()) {
  document["animation"] = {{"frames", {0, 12}}, {"fps", 24}};
  for (const Animated& field : fields) {
    document[json::json_pointer(field.pointer)] = {
        {"keys", {{first_key, field.from}, {last_key, field.to}}}, {"interpolation", "linear"}};
  }
  return document;
}

json still_at_shown_frame(const std::vector<Animated>& fields, json document = test::busy_scene()) {
  const double s = static_cast<double>(shown - first_key) / (last_key - first_key);
  for (const Animated& field : fields)
    document[json::json_pointer(field.pointer)] = lerp(field.from, field.to, s);
  return document;
}

bool same_bits(const Image& a, const Image& b) {
  return a.width() == b.width() && a.height() == b.height() &&
         a.pixels().size() == b.pixels().size() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixels().size() * sizeof(float)) == 0;
}

// Renders frame 0 and then frame `shown` of `fields`' animation of `base` the way `tessera
// render --frames` does, and the still scene; says whether the frame reused frame 0's
// geometry. `files`: where `base`'s mesh files and textures are.
void check_equivalence(const std::vector<Animated>& fields, bool expect_shared,
                       const json& base = test::busy_scene(), const SceneFiles* files = nullptr) {
  SceneFrames frames(animated_scene(fields, base).dump(), Limits{}, {}, files);
  const Renderer frame_zero(frames.take_first());
  const Renderer frame(frames.at(shown, frame_zero.scene()), frame_zero);
  EXPECT_EQ(frame.shares_geometry_with(frame_zero), expect_shared);
  const Image animated = render_local(frame, 2, 8).image;
  const Image still = test::render_image(still_at_shown_frame(fields, base), 1, 16, files);
  EXPECT_TRUE(same_bits(animated, still));
  // And the frame read whole, as a worker that holds no earlier frame reads it.
  const Renderer whole(
      parse_scene_frame(animated_scene(fields, base), shown, Limits{}, nullptr, files));
  EXPECT_TRUE(same_bits(render_local(whole, 1, 5).image, still));
  // The animation moves something: frame 0 differs.
  EXPECT_FALSE(same_bits(render_local(frame_zero, 1, 16).image, still));
}

TEST(AnimationDeterminism, Camera) {
  check_equivalence({{"/camera/eye", {0, 2, 7}, {2, 3, 6}},
                     {"/camera/look_at", {0, 0.8, 0}, {0.5, 0.5, 0}},
                     {"/camera/up", {0, 1, 0}, {0.3, 1, 0}},
                     {"/camera/fov_y", 40, 55}},
                    true);
}

TEST(AnimationDeterminism, Lights) {
  check_equivalence({{"/lights/0/position", {3, 5, 4}, {-2, 6, 3}},
                     {"/lights/0/intensity", 1, {0.5, 1.5, 2}},
                     {"/lights/1/direction", {1, -1, -0.5}, {0.5, -1, 0.5}},
                     {"/lights/1/cutoff", 30, 45},
                     {"/lights/1/exponent", 4, 1},
                     {"/lights/2/direction", {0.2, -1, -0.3}, {-0.5, -1, 0.2}}},
                    true);
}

TEST(AnimationDeterminism, Transforms) {
  check_equivalence({{"/objects/3/transform/0/rotate/degrees", 30, 120},
                     {"/objects/3/transform/0/rotate/axis", {0, 1, 0}, {0.2, 1, 0.1}},
                     {"/objects/3/transform/1/translate", {0, 0, 0}, {1, 0.2, 0.5}}},
                    false);
}

TEST(AnimationDeterminism, Materials) {
  check_equivalence({{"/materials/mirror/diffuse", 0.1, {0.6, 0.1, 0.1}},
                     {"/materials/mirror/specular", 0.8, 0.3},
                     {"/materials/mirror/shininess", 80, 10},
                     {"/materials/glass/ior", 1.5, 1.2},
                     {"/materials/glass/transmission", 0.9, {0.2, 0.9, 0.5}}},
                    true);
}

TEST(AnimationDeterminism, InlineMaterial) {
  // A track inside an object: the objects are read again, and built again.
  check_equivalence({{"/objects/3/material/diffuse", {0.8, 0.3, 0.2}, {0.1, 0.2, 0.9}}}, false);
}

TEST(AnimationDeterminism, BackgroundAndAmbient) {
  check_equivalence({{"/background", {0.3, 0.4, 0.6}, 0}, {"/ambient_light", 0.1, {0.4, 0.2, 0}}},
                    true);
}

// A small copy of a scene of examples/ (or of the build's generated ones).
json example(const std::filesystem::path& path) {
  json document = read_json_file(path);
  document["image"] = {{"width", 48}, {"height", 36}};
  return document;
}

TEST(AnimationDeterminism, TexturesAreSharedWithTheGeometry) {
  // Decoded and mip-mapped once, for frame 0; a moving camera changes every footprint.
  const std::filesystem::path dir = std::filesystem::path(TESSERA_BINARY_DIR) / "examples";
  const FolderSceneFiles files(dir);
  const json base = example(dir / "textured_globe.json");
  const json eye = base["camera"]["eye"];
  check_equivalence({{"/camera/eye", eye, {eye[0].get<double>() + 0.7, eye[1], eye[2]}},
                     {"/camera/fov_y", base["camera"].value("fov_y", 45.0), 30}},
                    true, base, &files);
}

TEST(AnimationDeterminism, AMeshFileThatTurns) {
  // A track in a mesh file's object: the whole text is read again for the frame, the
  // file with it, and its parts placed by the frame's transform.
  const std::filesystem::path dir = std::filesystem::path(TESSERA_SOURCE_DIR) / "examples";
  const FolderSceneFiles files(dir);
  check_equivalence({{"/objects/1/transform/0/rotate/axis", {0, 1, 0}, {0, 1, 0.2}},
                     {"/objects/1/transform/0/rotate/degrees", 0, 40}},
                    false, example(dir / "still_life.json"), &files);
}

TEST(AnimationDeterminism, TransmissionSwitchedOnRebuilds) {
  // A material that starts to transmit light changes how its shapes are registered.
  check_equivalence({{"/materials/mirror/transmission", 0, 0.5}}, false);
}

}  // namespace
}  // namespace tessera
