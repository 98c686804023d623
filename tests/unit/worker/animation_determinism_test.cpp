// Frame n of an animated scene renders bit for bit as the still scene that holds each
// track's value at n, for every kind of track; and a frame whose objects did not move
// reuses the geometry built for the frame before.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scene/scene_frames.hpp"
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

TEST(AnimationDeterminismTest, Camera) {
  check_equivalence({{"/camera/eye", {0, 2, 7}, {2, 3, 6}},
                     {"/camera/look_at", {0, 0.8, 0}, {0.5, 0.5, 0}},
                     {"/camera/up", {0, 1, 0}, {0.3, 1, 0}},
                     {"/camera/fov_y", 40, 55}},
                    true);
}

TEST(AnimationDeterminismTest, Lights) {
  check_equivalence({{"/lights/0/position", {3, 5, 4}, {-2, 6, 3}},
                     {"/lights/0/intensity", 1, {0.5, 1.5, 2}},
                     {"/lights/1/direction", {1, -1, -0.5}, {0.5, -1, 0.5}},
                     {"/lights/1/cutoff", 30, 45},
                     {"/lights/1/exponent", 4, 1},
                     {"/lights/2/direction", {0.2, -1, -0.3}, {-0.5, -1, 0.2}}},
                    true);
}

TEST(AnimationDeterminismTest, Transforms) {
  check_equivalence({{"/objects/3/transform/0/rotate/degrees", 30, 120},
                     {"/objects/3/transform/0/rotate/axis", {0, 1, 0}, {0.2, 1, 0.1}},
                     {"/objects/3/transform/1/translate", {0, 0, 0}, {1, 0.2, 0.5}}},
                    false);
}

TEST(AnimationDeterminismTest, Materials) {
  check_equivalence({{"/materials/mirror/diffuse", 0.1, {0.6, 0.1, 0.1}},
                     {"/materials/mirror/specular", 0.8, 0.3},
                     {"/materials/mirror/shininess", 80, 10},
                     {"/materials/glass/ior", 1.5, 1.2}},
                    true);
}

TEST(AnimationDeterminismTest, TransmissionReadsTheObjectsAgain) {
  // A transmission track may let a material begin or cease to let light through, which
  // changes how its shapes are registered: every frame reads and builds its objects.
  check_equivalence({{"/materials/glass/transmission", 0.9, {0.2, 0.9, 0.5}}}, false);
}

TEST(AnimationDeterminismTest, InlineMaterial) {
  // A track inside an object: the objects are read again, and built again.
  check_equivalence({{"/objects/3/material/diffuse", {0.8, 0.3, 0.2}, {0.1, 0.2, 0.9}}}, false);
}

TEST(AnimationDeterminismTest, BackgroundAndAmbient) {
  check_equivalence({{"/background", {0.3, 0.4, 0.6}, 0}, {"/ambient_light", 0.1, {0.4, 0.2, 0}}},
                    true);
}

// A small copy of a scene of examples/ (or of the build's generated ones).
json example(const std::filesystem::path& path) {
  json document = read_json_file(path);
  document["image"] = {{"width", 48}, {"height", 36}};
  return document;
}

TEST(AnimationDeterminismTest, TexturesAreSharedWithTheGeometry) {
  // Decoded and mip-mapped once, for frame 0; a moving camera changes every footprint.
  const std::filesystem::path dir = std::filesystem::path(TESSERA_BINARY_DIR) / "examples";
  const FolderSceneFiles files(dir);
  const json base = example(dir / "textured_globe.json");
  const json eye = base["camera"]["eye"];
  check_equivalence({{"/camera/eye", eye, {eye[0].get<double>() + 0.7, eye[1], eye[2]}},
                     {"/camera/fov_y", base["camera"].value("fov_y", 45.0), 30}},
                    true, base, &files);
}

TEST(AnimationDeterminismTest, AMeshFileThatTurns) {
  // A track in a mesh file's object: the whole text is read again for the frame, the
  // file with it, and its parts placed by the frame's transform.
  const std::filesystem::path dir = std::filesystem::path(TESSERA_SOURCE_DIR) / "examples";
  const FolderSceneFiles files(dir);
  check_equivalence({{"/objects/1/transform/0/rotate/axis", {0, 1, 0}, {0, 1, 0.2}},
                     {"/objects/1/transform/0/rotate/degrees", 0, 40}},
                    false, example(dir / "still_life.json"), &files);
}

// The busy scene and three tori: a mirror that turns and moves (objects/8), a glass one,
// flat and mirrored by a negative scale, that moves (9), and one that stands still with no
// transform (10).
json scene_with_meshes() {
  json document = test::busy_scene();
  json mirror = test::torus(24, 12, 0.45, 0.15, true);
  mirror["material"] = "mirror";
  mirror["transform"] = {{{"rotate", {{"axis", {1, 0, 0}}, {"degrees", 60}}}},
                         {{"translate", {0.4, 1.3, 1.2}}}};
  json glass = test::torus(20, 10, 0.35, 0.12, false);
  glass["material"] = "glass";
  glass["transform"] = {{{"scale", {-1, 0.8, 1}}}, {{"translate", {-0.6, 0.4, 2.4}}}};
  json still = test::torus(16, 10, 0.3, 0.1, true);
  still["transform"] = json::array();
  document["objects"].push_back(mirror);
  document["objects"].push_back(glass);
  document["objects"].push_back(still);
  return document;
}

TEST(AnimationDeterminismTest, MovingMeshesArePlacedAgainNotBuilt) {
  const std::vector<Animated> fields = {
      {"/objects/8/transform/0/rotate/degrees", 60, 150},
      {"/objects/8/transform/1/translate", {0.4, 1.3, 1.2}, {0.9, 1.0, 0.6}},
      {"/objects/9/transform/0/scale", {-1, 0.8, 1}, {-1.3, 0.6, 0.9}},
      {"/objects/9/transform/1/translate", {-0.6, 0.4, 2.4}, {-0.2, 0.6, 2.0}}};
  const json base = scene_with_meshes();
  check_equivalence(fields, false, base);

  // The frame built its own top-level BVH, but placed each moving torus's own BVH, the one
  // that frame 0 built, rather than building it again. The torus with no transform is in
  // the top-level BVH itself, as in a still scene.
  SceneFrames frames(animated_scene(fields, base).dump(), Limits{});
  const Renderer frame_zero(frames.take_first());
  const Renderer frame(frames.at(shown, frame_zero.scene()), frame_zero);
  EXPECT_FALSE(frame.shares_geometry_with(frame_zero));
  EXPECT_TRUE(frame.shares_meshes_with(frame_zero));
  for (std::uint32_t object : {8u, 9u}) {
    ASSERT_NE(frame_zero.geometry().mesh_bvh(object), nullptr) << object;
    EXPECT_EQ(frame.geometry().mesh_bvh(object), frame_zero.geometry().mesh_bvh(object)) << object;
  }
  EXPECT_EQ(frame.geometry().mesh_bvh(10), nullptr);
  // The analytic shapes have none.
  EXPECT_EQ(frame.geometry().mesh_bvh(1), nullptr);
}

TEST(AnimationDeterminismTest, APlacedMeshLooksAsItsTrianglesPlacedByHand) {
  // Each moving torus of scene_with_meshes() placed by its transform, against the same
  // torus with that transform applied to its corners and normals here (corners swapped
  // where it mirrors), which its BVH then holds as they are: the hits rebuilt in object
  // space and placed, the normals through the inverse transpose and the boxes of the glass
  // for the shadows must agree with those built in world space, within the rounding of
  // the corners to floats in either space.
  const json placed = scene_with_meshes();
  const Scene parsed = parse_scene(placed);
  json by_hand = placed;
  for (const std::size_t object : {std::size_t{8}, std::size_t{9}}) {
    const Mat4& transform = parsed.objects[object].transform;
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(transform)));
    const bool mirrors = glm::determinant(glm::dmat3(transform)) < 0.0;
    json& mesh = by_hand["objects"][object];
    for (json& p : mesh["positions"]) {
      const Vec3 q(transform *
                   glm::dvec4(p[0].get<double>(), p[1].get<double>(), p[2].get<double>(), 1.0));
      p = {q.x, q.y, q.z};
    }
    if (mesh.contains("normals"))
      for (json& n : mesh["normals"]) {
        const Vec3 m = glm::normalize(
            normal_matrix * Vec3(n[0].get<double>(), n[1].get<double>(), n[2].get<double>()));
        n = {m.x, m.y, m.z};
      }
    if (mirrors)
      for (json& t : mesh["triangles"]) std::swap(t[1], t[2]);
    mesh.erase("transform");
  }
  const Image a = test::render_image(placed, 2, 16);
  const Image b = test::render_image(by_hand, 2, 16);
  ASSERT_EQ(a.pixels().size(), b.pixels().size());
  std::size_t differing = 0;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) {
      float worst = 0;
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::fabs(a.pixel(x, y)[c] - b.pixel(x, y)[c]));
      differing += worst > 1e-3f;
    }
  EXPECT_LE(differing, 6u) << "of " << a.width() * a.height() << " pixels";
  // And the tori are in the picture: without them it is another image.
  json without = placed;
  without["objects"].erase(8);
  const Image c = test::render_image(without, 2, 16);
  EXPECT_FALSE(same_bits(a, c));
}

TEST(AnimationDeterminismTest, MovingMeshesRenderTheSameOnAnyTiling) {
  // The frame's pixels on one thread and 16-pixel tiles, and on two and 7-pixel tiles.
  const std::vector<Animated> fields = {{"/objects/8/transform/0/rotate/degrees", 60, 150}};
  SceneFrames frames(animated_scene(fields, scene_with_meshes()).dump(), Limits{});
  const Renderer frame_zero(frames.take_first());
  const Renderer frame(frames.at(shown, frame_zero.scene()), frame_zero);
  EXPECT_TRUE(same_bits(render_local(frame, 1, 16).image, render_local(frame, 2, 7).image));
}

TEST(AnimationDeterminismTest, TransmissionSwitchedOnRebuilds) {
  // A material that starts to transmit light changes how its shapes are registered.
  check_equivalence({{"/materials/mirror/transmission", 0, 0.5}}, false);
}

TEST(AnimationDeterminismTest, TransmissionSwitchedOnRebuildsMeshesToo) {
  // The frame is read whole again: the torus with no transform, in the scene's own BVH,
  // is built again from its arrays (which frame 0 freed once Embree held them).
  check_equivalence({{"/materials/mirror/transmission", 0, 0.5}}, false, scene_with_meshes());
}

TEST(AnimationDeterminismTest, AMeshThatStartsStillIsPlacedOnceItMoves) {
  // Frame 0 has the torus where its arrays put it; frame `shown`, moved, places a BVH of
  // its own, which a later frame made from that one places again.
  json base = scene_with_meshes();
  base["objects"][10]["transform"] = {{{"translate", {0, 0, 0}}}};
  const std::vector<Animated> moving = {
      {"/objects/10/transform/0/translate", {0, 0, 0}, {0.8, 0.3, -0.4}}};
  check_equivalence(moving, false, base);
  SceneFrames frames(animated_scene(moving, base).dump(), Limits{});
  const Renderer frame_zero(frames.take_first());
  EXPECT_EQ(frame_zero.geometry().mesh_bvh(10), nullptr);
  const Renderer moved(frames.at(shown, frame_zero.scene()), frame_zero);
  ASSERT_NE(moved.geometry().mesh_bvh(10), nullptr);
  const Renderer later(frames.at(shown + 1, moved.scene()), moved);
  EXPECT_EQ(later.geometry().mesh_bvh(10), moved.geometry().mesh_bvh(10));
}

}  // namespace
}  // namespace tessera
