// Shapes, transforms and the robustness of secondary rays.
#include <cmath>

#include <gtest/gtest.h>

#include "tests/unit/worker/render_helpers.hpp"

namespace tessera {
namespace {

using test::json;
using test::pinhole_scene;
using test::render_image;
using test::render_pixel;

TEST(GeometryTest, NonUniformlyScaledSphereIsAnEllipsoid) {
  // x²/4 + y² + z² = 1, hit by a ray along -z at x = 1.5: z = √(1 - 1.5²/4) and the
  // normal is ∝ (x/4, y, z). Light travels along -z, so the pixel is K_D · n.z.
  json scene = pinhole_scene({1.5, 0, 10}, {1.5, 0, 0});
  scene["lights"].push_back({{"type", "directional"}, {"direction", {0, 0, -1}}, {"intensity", 1}});
  scene["objects"].push_back({{"type", "sphere"},
                              {"center", {0, 0, 0}},
                              {"radius", 1},
                              {"transform", {{{"scale", {2, 1, 1}}}}},
                              {"material", {{"ambient", 0}, {"diffuse", 0.5}}}});
  const double z = std::sqrt(1.0 - 1.5 * 1.5 / 4.0);
  const double n_z = z / glm::length(Vec3(1.5 / 4.0, 0, z));
  EXPECT_NEAR(render_pixel(scene).r, 0.5 * n_z, 1e-5);

  scene["objects"][0].erase("transform");  // the unit sphere is missed at x = 1.5
  EXPECT_EQ(render_pixel(scene).r, 0.0);
}

TEST(GeometryTest, RotatedUniformlyScaledSphereIsASphereOfScaledRadius) {
  // Such a transform takes the renderer's world-space shortcut for spheres. Scaled by 2
  // about the origin, then moved to (0, 0, -3): a sphere of radius 2 at (0, 0, -3),
  // rotated about its own centre, which changes nothing. A ray along -z at x = 1.2 meets
  // it at z = -3 + √(4 - 1.44) with the normal (1.2, 0, √2.56) / 2.
  json scene = pinhole_scene({1.2, 0, 10}, {1.2, 0, 0});
  scene["lights"].push_back({{"type", "directional"}, {"direction", {0, 0, -1}}, {"intensity", 1}});
  scene["objects"].push_back({{"type", "sphere"},
                              {"center", {0, 0, 0}},
                              {"radius", 1},
                              {"transform",
                               {{{"rotate", {{"axis", {1, 1, 0}}, {"degrees", 37}}}},
                                {{"scale", 2}},
                                {{"translate", {0, 0, -3}}}}},
                              {"material", {{"ambient", 0}, {"diffuse", 0.5}}}});
  EXPECT_NEAR(render_pixel(scene).r, 0.5 * std::sqrt(4.0 - 1.44) / 2.0, 1e-6);
  // Just outside the radius, the ray passes by.
  scene["camera"]["eye"] = {2.001, 0, 10};
  scene["camera"]["look_at"] = {2.001, 0, 0};
  EXPECT_EQ(render_pixel(scene).r, 0.0);
}

TEST(GeometryTest, TheNearestOfSeveralPlanesIsHit) {
  // All the planes of a scene share one Embree primitive; the nearest must win whatever the
  // order of the objects, and a transmissive plane in front lets the next one show through.
  auto plane_at = [](double z, double emission, json material_extra = json::object()) {
    json material = {{"ambient", 0}, {"diffuse", 0}, {"emission", emission}};
    material.update(material_extra);
    return json{
        {"type", "plane"}, {"point", {0, 0, z}}, {"normal", {0, 0, 1}}, {"material", material}};
  };
  json scene = pinhole_scene({0, 0, 10}, {0, 0, 0});
  scene["objects"] = {plane_at(-4, 0.25), plane_at(2, 0.5), plane_at(-1, 0.75)};
  EXPECT_EQ(render_pixel(scene).r, 0.5f);
  scene["objects"][1] = plane_at(2, 0.0, {{"transmission", 0.5}});  // now see-through
  EXPECT_NEAR(render_pixel(scene).r, 0.5 * 0.75, 1e-12);
}

TEST(GeometryTest, PacketsFindWhateverIsNearestOfAnOpaquePlaneAndTheRest) {
  // Packets test opaque planes themselves and let Embree look only nearer than the plane:
  // a sphere behind the plane stays hidden, one in front of it is seen, and one cut by it
  // shows its cap above the plane.
  auto emitting = [](double emission) {
    return json{{"ambient", 0}, {"diffuse", 0}, {"emission", emission}};
  };
  json scene = pinhole_scene({0, 10, 0}, {0, 0, 0}, {0, 0, -1});  // looking down at y = 0
  scene["objects"] = {
      {{"type", "plane"},
       {"point", {0, 0, 0}},
       {"normal", {0, 1, 0}},
       {"material", emitting(0.25)}},
      {{"type", "sphere"}, {"center", {0, -3, 0}}, {"radius", 1}, {"material", emitting(0.5)}}};
  EXPECT_EQ(render_pixel(scene).r, 0.25f);
  scene["objects"][1]["center"] = {0, 3, 0};
  EXPECT_EQ(render_pixel(scene).r, 0.5f);
  scene["objects"][1]["center"] = {0, -0.5, 0};
  EXPECT_EQ(render_pixel(scene).r, 0.5f);
}

TEST(GeometryTest, BoundedPacketsFindOnlyWhatTheirMaskHoldsBeforeTheirReach) {
  // The shadow walk's packets: each lane goes only as far as its own reach, and sees only
  // the surfaces under the mask. Straight down from y = 10: a glass sphere whose top is at
  // y = 4, then the opaque floor at y = 0.
  json scene = pinhole_scene({0, 10, 0}, {0, 0, 0}, {0, 0, -1});
  scene["objects"] = {{{"type", "plane"},
                       {"point", {0, 0, 0}},
                       {"normal", {0, 1, 0}},
                       {"material", {{"diffuse", 1}}}},
                      {{"type", "sphere"},
                       {"center", {0, 3, 0}},
                       {"radius", 1},
                       {"material", {{"transmission", 0.5}, {"ior", 1.5}}}}};
  const Renderer renderer(parse_scene(scene));
  const SceneGeometry& geometry = renderer.geometry();
  RayPacket packet;
  float reach[kPacketSize] = {};
  // Lanes 0-3 go through the sphere's centre, 4-7 pass it by at x = 3; reaches 5.5 (short
  // of the sphere), 6.5 (into it), 11 (to the floor) and infinity.
  const float reaches[4] = {5.5f, 6.5f, 11.0f, kInfinity};
  for (int i = 0; i < 8; ++i) {
    packet.active[i] = true;
    packet.set(i, Ray{{i < 4 ? 0.0f : 3.0f, 10.0f, 0.0f}, {0.0f, -1.0f, 0.0f}});
    reach[i] = reaches[i % 4];
  }
  SurfaceHit hits[kPacketSize];
  bool found[kPacketSize];
  const std::uint32_t floor = 0, sphere = 1;
  geometry.intersect(packet, reach, kAnyMask, hits, found);
  const bool any_expected[8] = {false, true, true, true, false, false, true, true};
  const std::uint32_t any_object[8] = {0, sphere, sphere, sphere, 0, 0, floor, floor};
  const double any_t[8] = {0, 6, 6, 6, 0, 0, 10, 10};
  for (int i = 0; i < 8; ++i) {
    ASSERT_EQ(found[i], any_expected[i]) << "lane " << i;
    if (!found[i]) continue;
    EXPECT_EQ(hits[i].object, any_object[i]) << "lane " << i;
    EXPECT_NEAR(hits[i].t, any_t[i], 1e-6) << "lane " << i;
  }
  for (int i = 8; i < kPacketSize; ++i) EXPECT_FALSE(found[i]) << "lane " << i;
  // Under the transmissive mask the floor is not there, however far the lane goes.
  geometry.intersect(packet, reach, kTransmissiveMask, hits, found);
  for (int i = 0; i < 8; ++i) {
    ASSERT_EQ(found[i], i >= 1 && i < 4) << "lane " << i;
    if (found[i]) {
      EXPECT_EQ(hits[i].object, sphere) << "lane " << i;
    }
  }
}

TEST(GeometryTest, OpaquePlanesStayOutOfEmbreeAndSingleRaysStillMeetThem) {
  // Straight down from y = 10 onto a sphere whose top is at y = 4, over the floor at y = 0.
  json scene = pinhole_scene({0, 10, 0}, {0, 0, 0}, {0, 0, -1});
  scene["objects"] = {{{"type", "plane"},
                       {"point", {0, 0, 0}},
                       {"normal", {0, 1, 0}},
                       {"material", {{"diffuse", 1}}}},
                      {{"type", "sphere"}, {"center", {0, 3, 0}}, {"radius", 1}}};
  const Renderer renderer(parse_scene(scene));
  const SceneGeometry& geometry = renderer.geometry();
  // Embree's box around its scene is the sphere's alone: the plane's would be everywhere.
  RTCBounds bounds;
  rtcGetSceneBounds(geometry.embree_scene(), &bounds);
  EXPECT_LT(bounds.upper_y, 4.1f);
  EXPECT_GT(bounds.lower_y, 1.9f);
  const EmbreeDevice device;
  const SceneGeometry whole(renderer.scene(), device, OpaquePlanes::also_in_embree);
  rtcGetSceneBounds(whole.embree_scene(), &bounds);
  EXPECT_GT(bounds.upper_y, 1e17f);

  const std::uint32_t floor = 0, sphere = 1;
  const Ray onto_sphere{{0.0f, 10.0f, 0.0f}, {0.0f, -1.0f, 0.0f}};
  const Ray beside_it{{3.0f, 10.0f, 0.0f}, {0.0f, -1.0f, 0.0f}};
  for (const SceneGeometry* g : {&geometry, &whole}) {
    const auto first = g->intersect(onto_sphere, kInfinity);
    ASSERT_TRUE(first.has_value());
    EXPECT_EQ(first->object, sphere);
    EXPECT_NEAR(first->t, 6.0, 1e-9);
    const auto floor_hit = g->intersect(beside_it, kInfinity);
    ASSERT_TRUE(floor_hit.has_value());
    EXPECT_EQ(floor_hit->object, floor);
    EXPECT_EQ(floor_hit->t, 10.0);
    EXPECT_EQ(floor_hit->normal, Vec3(0, 1, 0));
    EXPECT_FALSE(g->intersect(beside_it, 9.5f).has_value());
    EXPECT_FALSE(g->intersect(beside_it, kInfinity, kTransmissiveMask | kOpaqueSolidMask));
    EXPECT_TRUE(g->occluded(beside_it, 10.5f, kOpaqueMask));
    EXPECT_FALSE(g->occluded(beside_it, 9.5f, kOpaqueMask));
    EXPECT_FALSE(g->occluded(beside_it, 10.5f, kOpaqueSolidMask));
    EXPECT_TRUE(g->occluded(onto_sphere, 6.5f, kOpaqueSolidMask));
  }
}

TEST(GeometryTest, TransformStepsApplyInOrder) {
  // Scale by 2, then translate by x+3: the unit sphere covers x in [1, 5]. The other order
  // would cover [4, 8], missing the ray at x = 1.5.
  json scene = pinhole_scene({1.5, 0, 10}, {1.5, 0, 0});
  scene["ambient_light"] = 1;
  scene["objects"].push_back({{"type", "sphere"},
                              {"center", {0, 0, 0}},
                              {"radius", 1},
                              {"transform", {{{"scale", 2}}, {{"translate", {3, 0, 0}}}}},
                              {"material", {{"ambient", 1}}}});
  EXPECT_EQ(render_pixel(scene).r, 1.0);
  scene["objects"][0]["transform"] = {{{"translate", {3, 0, 0}}}, {{"scale", 2}}};
  EXPECT_EQ(render_pixel(scene).r, 0.0);
}

TEST(GeometryTest, BoxUnderMirroringTransformStaysSolid) {
  // A mirroring scale flips triangle winding; refraction must still see the box as a
  // solid (enter then leave), so a ray at normal incidence passes straight through.
  json scene = pinhole_scene({0.3, 0.2, 5}, {0.3, 0.2, 0});
  scene["objects"].push_back(
      {{"type", "box"},
       {"min", {-1, -1, -1}},
       {"max", {1, 1, 1}},
       {"transform", {{{"scale", {-1, 1, 1}}}}},
       {"material", {{"ambient", 0}, {"diffuse", 0}, {"transmission", 0.5}, {"ior", 1.5}}}});
  scene["background"] = 1;
  EXPECT_NEAR(render_pixel(scene).r, 0.25, 1e-6);
}

TEST(GeometryTest, BoxesAreMetOnEachFaceFromOutsideAndInside) {
  // Boxes are tested analytically: along the axes in world space when the transform only
  // scales and moves them (the first), in object space otherwise (the second).
  const json transforms[2] = {{{{"scale", {2, 1, -0.5}}}, {{"translate", {1, -1, 2}}}},
                              {{{"rotate", {{"axis", {1, 1, 1}}, {"degrees", 40}}}},
                               {{"scale", {1, 3, 1}}},
                               {{"translate", {-2, 0, 1}}}}};
  const Vec3 lo(1, 2, 3), hi(2, 4, 7);
  for (const json& steps : transforms) {
    json scene = pinhole_scene({0, 0, 50}, {0, 0, 0});
    scene["objects"] = {{{"type", "box"},
                         {"min", {lo.x, lo.y, lo.z}},
                         {"max", {hi.x, hi.y, hi.z}},
                         {"transform", steps}}};
    const Renderer renderer(parse_scene(scene));
    const SceneGeometry& geometry = renderer.geometry();
    const Mat4& m = renderer.scene().objects[0].transform;
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(m)));
    const Vec3 centre(m * glm::dvec4((lo + hi) / 2.0, 1.0));
    RayPacket packet;
    Vec3 normals[6];
    for (int face = 0; face < 6; ++face) {
      const int axis = face / 2;
      Vec3 middle = (lo + hi) / 2.0;
      middle[axis] = face % 2 == 1 ? hi[axis] : lo[axis];
      Vec3 outward(0.0);
      outward[axis] = face % 2 == 1 ? 1.0 : -1.0;
      const Vec3 point(m * glm::dvec4(middle, 1.0));
      const Vec3 n = glm::normalize(normal_matrix * outward);
      normals[face] = n;
      // From 3 units out, straight at the face's middle.
      const Ray in{glm::vec3(point + 3.0 * n), glm::vec3(-n)};
      const auto hit = geometry.intersect(in, kInfinity);
      ASSERT_TRUE(hit.has_value()) << "face " << face;
      EXPECT_NEAR(hit->t, 3.0, 1e-5) << "face " << face;
      EXPECT_NEAR(glm::length(hit->normal - n), 0.0, 1e-12) << "face " << face;
      EXPECT_NEAR(glm::dot(hit->position - point, n), 0.0, 1e-12) << "face " << face;
      EXPECT_NEAR(glm::length(hit->position - point), 0.0, 1e-5) << "face " << face;
      EXPECT_FALSE(geometry.occluded(in, 2.9f)) << "face " << face;
      EXPECT_TRUE(geometry.occluded(in, 3.1f)) << "face " << face;
      // From the centre, out through the face's middle: the far side, with its outward
      // normal.
      const Ray out{glm::vec3(centre), glm::vec3(glm::normalize(point - centre))};
      const auto exit = geometry.intersect(out, kInfinity);
      ASSERT_TRUE(exit.has_value()) << "face " << face;
      EXPECT_NEAR(exit->t, glm::length(point - centre), 1e-5) << "face " << face;
      EXPECT_NEAR(glm::length(exit->normal - n), 0.0, 1e-12) << "face " << face;
      // Turned away from the box, the same ray meets nothing.
      EXPECT_FALSE(geometry.intersect(Ray{in.origin, -in.direction}, kInfinity)) << "face " << face;
      packet.active[face] = true;
      packet.set(face, in);
    }
    // A packet finds the very hits single rays do.
    SurfaceHit hits[kPacketSize];
    bool found[kPacketSize];
    geometry.intersect(packet, hits, found);
    for (int face = 0; face < 6; ++face) {
      ASSERT_TRUE(found[face]) << "face " << face;
      const auto single = geometry.intersect(packet.ray(face), kInfinity);
      EXPECT_EQ(hits[face].t, single->t) << "face " << face;
      EXPECT_EQ(hits[face].position, single->position) << "face " << face;
      EXPECT_EQ(hits[face].normal, normals[face]) << "face " << face;
    }
  }
}

// Every pixel of a scene where secondary rays must not hit their own surface: a mirror or
// a clear glass sphere under a white sky. Any self-intersection darkens a pixel.
void expect_uniform_sky(const Vec3& centre, double radius, const json& material) {
  json scene = {{"image", {{"width", 48}, {"height", 48}}},
                {"camera",
                 {{"eye", {centre.x, centre.y, centre.z + 3 * radius}},
                  {"look_at", {centre.x, centre.y, centre.z}}}},
                {"background", 1},
                {"ambient_light", 0},
                {"render", {{"max_depth", 8}}},
                {"objects",
                 {{{"type", "sphere"},
                   {"center", {centre.x, centre.y, centre.z}},
                   {"radius", radius},
                   {"material", material}}}}};
  const Image image = render_image(scene);
  int dark = 0;
  for (float v : image.pixels()) dark += std::fabs(v - 1.0f) > 1e-5f;
  EXPECT_EQ(dark, 0) << "centre " << centre.x << " radius " << radius;
}

TEST(GeometryTest, NoSelfIntersectionNearOrFarSmallOrLarge) {
  const json mirror = {{"ambient", 0}, {"diffuse", 0}, {"reflection", 1}};
  const json clear_glass = {{"ambient", 0}, {"diffuse", 0}, {"transmission", 1}, {"ior", 1.5}};
  for (const auto& [centre, radius] :
       {std::pair{Vec3(0, 0, 0), 1.0}, std::pair{Vec3(1e5, -2e5, 3e5), 10.0},
        std::pair{Vec3(0, 0, 0), 1e4}, std::pair{Vec3(2, 1, 0), 1e-3}}) {
    expect_uniform_sky(centre, radius, mirror);
    expect_uniform_sky(centre, radius, clear_glass);
  }
}

// A floor 1e5 units from the origin, lit from above and seen from 8 units away: every
// pixel of the lower half of the image is K_D·(N·L), with no shadow acne.
void expect_clean_far_floor(const json& floor, const Vec3& normal) {
  const Vec3 far(1e5, 0, -1e5);
  const Vec3 light(-0.3, -1, -0.2);
  json scene = {{"image", {{"width", 64}, {"height", 48}}},
                {"camera", {{"eye", {far.x, 3, far.z + 8}}, {"look_at", {far.x, 0, far.z}}}},
                {"ambient_light", 0},
                {"lights", {{{"type", "directional"}, {"direction", {light.x, light.y, light.z}}}}},
                {"objects", {floor}}};
  scene["objects"][0]["material"] = {{"ambient", 0}, {"diffuse", 0.5}};
  const double expected = 0.5 * glm::dot(glm::normalize(normal), -glm::normalize(light));
  const Image image = render_image(scene);
  int wrong = 0;
  for (int y = 24; y < 48; ++y)
    for (int x = 0; x < 64; ++x) wrong += std::fabs(image.pixel(x, y)[0] - expected) > 1e-5;
  EXPECT_EQ(wrong, 0) << floor.dump();
}

TEST(GeometryTest, NoShadowAcneOnALargeFarAwayFloor) {
  // A slightly tilted plane: its points do not round to floats lying on it.
  expect_clean_far_floor(
      {{"type", "plane"}, {"point", {1e5, 0, -1e5}}, {"normal", {0.02, 1, 0.03}}}, {0.02, 1, 0.03});
  // The top of a huge box: triangles, intersected by Embree in single precision.
  expect_clean_far_floor({{"type", "box"}, {"min", {0, -1, -2e5}}, {"max", {2e5, 0, 0}}},
                         {0, 1, 0});
}

TEST(GeometryTest, CheckerOnACellBoundaryHasNoSpeckle) {
  // The floor at y = 0 lies exactly on a cell boundary of a unit checkerboard. Seen from
  // straight above, pixel (i, j) hits x = ex + sx·h·tan(fov/2), z = ez - sy·h·tan(fov/2).
  const int size = 96;
  const double h = 6, ex = 0.37, ez = 0.21, fov = 60;
  json scene = {
      {"image", {{"width", size}, {"height", size}}},
      {"camera",
       {{"eye", {ex, h, ez}}, {"look_at", {ex, 0, ez}}, {"up", {0, 0, -1}}, {"fov_y", fov}}},
      {"ambient_light", 0},
      {"lights", {{{"type", "directional"}, {"direction", {0, -1, 0}}}}},
      {"objects",
       {{{"type", "plane"},
         {"point", {0, 0, 0}},
         {"normal", {0, 1, 0}},
         {"material",
          {{"ambient", 0}, {"diffuse", 0.8}, {"checker", {{"size", 1}, {"diffuse", 0.2}}}}}}}}};
  const Image image = render_image(scene);
  const double half = h * std::tan(glm::radians(fov / 2));
  int checked = 0, wrong = 0;
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const double x = ex + (2.0 * (i + 0.5) / size - 1.0) * half;
      const double z = ez - (1.0 - 2.0 * (j + 0.5) / size) * half;
      if (std::fabs(x - std::round(x)) < 1e-3 || std::fabs(z - std::round(z)) < 1e-3) continue;
      // The point falls in the cell just below the floor: floor(y) = -1.
      const bool odd = (static_cast<long>(std::floor(x) + std::floor(z)) - 1) % 2 != 0;
      ++checked;
      wrong += std::fabs(image.pixel(i, j)[0] - (odd ? 0.2f : 0.8f)) > 1e-6f;
    }
  EXPECT_GT(checked, size * size * 9 / 10);
  EXPECT_EQ(wrong, 0);
}

TEST(GeometryTest, SmoothMeshNormalsAreInterpolated) {
  // One triangle in z = 0 whose vertex normals all tilt 60° towards +x: lit along -z, a
  // flat normal gives K_D, the interpolated one K_D · cos 60°.
  json scene = pinhole_scene({0.2, 0.2, 5}, {0.2, 0.2, 0});
  scene["lights"].push_back({{"type", "directional"}, {"direction", {0, 0, -1}}});
  const double s = std::sin(glm::radians(60.0)), c = std::cos(glm::radians(60.0));
  scene["objects"].push_back({{"type", "mesh"},
                              {"positions", {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}}},
                              {"triangles", {{0, 1, 2}}},
                              {"normals", {{s, 0, c}, {s, 0, c}, {s, 0, c}}},
                              {"thin", true},
                              {"material", {{"ambient", 0}, {"diffuse", 1}}}});
  EXPECT_NEAR(render_pixel(scene).r, c, 1e-5);
  scene["objects"][0].erase("normals");
  EXPECT_NEAR(render_pixel(scene).r, 1.0, 1e-6);
}

TEST(GeometryTest, AMeshHitHasTheNormalOfTheFloatCornersEmbreeIntersected) {
  // The hit is rebuilt on the triangle Embree saw, whose corners are floats: the normal
  // (worked out when the mesh is built) must be the one of those floats, bit for bit, not of
  // the doubles they were rounded from.
  json scene = pinhole_scene({0.1, 0.1, 5}, {0.1, 0.1, 0});
  const double corners[3][3] = {{-0.7, -0.3, 0.1}, {0.9, -0.2, 0.3}, {0.1, 0.8, -0.2}};
  scene["objects"].push_back({{"type", "mesh"},
                              {"positions", corners},
                              {"triangles", {{0, 1, 2}}},
                              {"material", {{"diffuse", 1}}}});
  const Renderer renderer(parse_scene(scene));
  const auto hit =
      renderer.geometry().intersect(renderer.camera().ray_through(0.5, 0.5), kInfinity);
  ASSERT_TRUE(hit.has_value());
  // Rounded through memory the compiler must really write: GCC 12's vectoriser was seen to
  // drop a float rounding it could see through (tracer/scene_geometry.cpp).
  auto rounded = [](double value) {
    volatile float f = static_cast<float>(value);
    return static_cast<double>(f);
  };
  Vec3 floats[3];
  Vec3 doubles[3];
  for (int k = 0; k < 3; ++k) {
    floats[k] = Vec3(rounded(corners[k][0]), rounded(corners[k][1]), rounded(corners[k][2]));
    doubles[k] = Vec3(corners[k][0], corners[k][1], corners[k][2]);
  }
  const Vec3 expected = glm::normalize(glm::cross(floats[1] - floats[0], floats[2] - floats[0]));
  EXPECT_EQ(hit->normal.x, expected.x);
  EXPECT_EQ(hit->normal.y, expected.y);
  EXPECT_EQ(hit->normal.z, expected.z);
  EXPECT_NE(glm::normalize(glm::cross(doubles[1] - doubles[0], doubles[2] - doubles[0])), expected);
}

}  // namespace
}  // namespace tessera
