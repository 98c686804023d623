// Cylinders and cones: hits with known analytic answers, from outside and from inside,
// under transforms, the solid's refraction, robustness of secondary rays, and packets that
// give the bits of single rays.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "tests/unit/worker/render_helpers.hpp"

namespace tessera {
namespace {

using test::json;
using test::pinhole_scene;
using test::render_pixel;

// A scene of the one object, whose geometry the tests query directly.
struct OneObject {
  explicit OneObject(const json& object) : renderer(parse_scene(scene_of(object))) {}
  static json scene_of(const json& object) {
    json scene = pinhole_scene({0, 0, 50}, {0, 0, 0});
    scene["objects"] = {object};
    return scene;
  }
  const SceneGeometry& geometry() const { return renderer.geometry(); }
  std::optional<SurfaceHit> hit(const Vec3& origin, const Vec3& direction) const {
    return geometry().intersect(Ray{glm::vec3(origin), glm::vec3(glm::normalize(direction))},
                                kInfinity);
  }
  Renderer renderer;
};

json cylinder(const Vec3& c, double radius, double height) {
  return {
      {"type", "cylinder"}, {"center", {c.x, c.y, c.z}}, {"radius", radius}, {"height", height}};
}

json cone(const Vec3& c, double radius, double height) {
  return {{"type", "cone"}, {"center", {c.x, c.y, c.z}}, {"radius", radius}, {"height", height}};
}

void expect_near(const Vec3& actual, const Vec3& expected, double tolerance,
                 const std::string& what) {
  EXPECT_NEAR(glm::length(actual - expected), 0.0, tolerance)
      << what << ": (" << actual.x << ", " << actual.y << ", " << actual.z << ") instead of ("
      << expected.x << ", " << expected.y << ", " << expected.z << ")";
}

TEST(QuadricGeometryTest, CylinderSideAndCapsAtKnownDistances) {
  // Radius 1, from y = 0 to y = 2.
  const OneObject scene(cylinder({0, 1, 0}, 1, 2));
  // Along -z at x = 0.6 (as a float), y = 1.5: the side at z = √(1 - x²), with the normal
  // (x, 0, z).
  const double x = static_cast<float>(0.6);
  const double z = std::sqrt(1 - x * x);
  auto hit = scene.hit({x, 1.5, 5}, {0, 0, -1});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 5 - z, 1e-15);
  expect_near(hit->normal, {x, 0, z}, 1e-15, "side normal");
  expect_near(hit->position, {x, 1.5, z}, 1e-15, "side point");
  EXPECT_NEAR(std::hypot(hit->position.x, hit->position.z), 1.0, 1e-15);
  // Straight down onto the top cap, and straight up onto the bottom one.
  hit = scene.hit({0.3, 5, -0.2}, {0, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 3.0);
  EXPECT_EQ(hit->normal, Vec3(0, 1, 0));
  EXPECT_EQ(hit->position.y, 2.0);
  hit = scene.hit({0.3, -4, -0.2}, {0, 1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 4.0);
  EXPECT_EQ(hit->normal, Vec3(0, -1, 0));
  EXPECT_EQ(hit->position.y, 0.0);
  // A slanted ray onto the top cap: from (0, 3, 2) towards (0, 2, 0.5), t = √(1 + 1.5²).
  hit = scene.hit({0, 3, 2}, {0, -1, -1.5});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, std::sqrt(3.25), 1e-6);
  EXPECT_EQ(hit->normal, Vec3(0, 1, 0));
  expect_near(hit->position, {0, 2, 0.5}, 1e-6, "cap point");
  // Just outside the radius the side is missed, along z and along y past the caps' rim.
  EXPECT_FALSE(scene.hit({1.0001, 1, 5}, {0, 0, -1}));
  EXPECT_TRUE(scene.hit({0.9999, 1, 5}, {0, 0, -1}));
  EXPECT_FALSE(scene.hit({0, 5, 1.0001}, {0, -1, 0}));
  EXPECT_TRUE(scene.hit({0, 5, 0.9999}, {0, -1, 0}));
  // Just above the top, and below the bottom.
  EXPECT_FALSE(scene.hit({0, 2.0001, 5}, {0, 0, -1}));
  EXPECT_FALSE(scene.hit({0, -0.0001, 5}, {0, 0, -1}));
  // Turned away, nothing.
  EXPECT_FALSE(scene.hit({0.6, 1.5, 5}, {0, 0, 1}));
}

TEST(QuadricGeometryTest, CylinderFromInsideMeetsItsOutwardSurface) {
  const OneObject scene(cylinder({0, 1, 0}, 1, 2));
  auto hit = scene.hit({0, 1, 0}, {1, 0, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 1.0);
  EXPECT_EQ(hit->normal, Vec3(1, 0, 0));
  hit = scene.hit({0.2, 1, 0.1}, {0, 1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 1.0);
  EXPECT_EQ(hit->normal, Vec3(0, 1, 0));
  hit = scene.hit({0.2, 1, 0.1}, {0, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->normal, Vec3(0, -1, 0));
  // Out near the rim: the side at y = 1.9, not the cap above it.
  hit = scene.hit({0, 1, 0}, {1, 0.9, 0});
  ASSERT_TRUE(hit);
  expect_near(hit->position, {1, 1.9, 0}, 1e-6, "near the rim");
  EXPECT_EQ(hit->normal, Vec3(1, 0, 0));
}

TEST(QuadricGeometryTest, ConeSideBaseAndApex) {
  // Radius 1, height 2: the base at y = -1, the apex at y = 1. At height y the radius is
  // (1 - y) / 2, and the side's outward normal is (2·u, 1) / √5 for u across the axis.
  const OneObject scene(cone({0, 0, 0}, 1, 2));
  auto hit = scene.hit({0, 0, 5}, {0, 0, -1});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 4.5, 1e-12);
  expect_near(hit->normal, Vec3(0, 1, 2) / std::sqrt(5.0), 1e-12, "side normal");
  expect_near(hit->position, {0, 0, 0.5}, 1e-12, "side point");
  // The base cap from below.
  hit = scene.hit({0.2, -5, 0.1}, {0, 1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 4.0);
  EXPECT_EQ(hit->normal, Vec3(0, -1, 0));
  EXPECT_EQ(hit->position.y, -1.0);
  // From inside, out through the base and the side.
  hit = scene.hit({0.1, -0.5, 0}, {0, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 0.5);
  EXPECT_EQ(hit->normal, Vec3(0, -1, 0));
  hit = scene.hit({0, -0.5, 0}, {-1, 0, 0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 0.75, 1e-12);
  expect_near(hit->normal, Vec3(-2, 1, 0) / std::sqrt(5.0), 1e-12, "side from inside");
  // Down the axis onto the apex, whose normal points up the axis.
  hit = scene.hit({0, 5, 0}, {0, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 4.0);
  EXPECT_EQ(hit->normal, Vec3(0, 1, 0));
  EXPECT_EQ(hit->position, Vec3(0, 1, 0));
  // Up the axis from inside, out through the apex.
  hit = scene.hit({0, 0, 0}, {0, 1, 0});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 1.0);
  EXPECT_EQ(hit->normal, Vec3(0, 1, 0));
  // Just outside the base's rim, and just outside the side halfway up.
  EXPECT_FALSE(scene.hit({1.0001, -5, 0}, {0, 1, 0}));
  EXPECT_TRUE(scene.hit({0.9999, -5, 0}, {0, 1, 0}));
  EXPECT_FALSE(scene.hit({0.5001, 0, 5}, {0, 0, -1}));
  EXPECT_FALSE(scene.hit({0, 0, 5}, {0, 0, 1}));
}

TEST(QuadricGeometryTest, RaysGrazingTheConesApex) {
  const OneObject scene(cone({0, 0, 0}, 1, 2));
  // Just below the apex the cone is 5e-5 wide: met there, on the side, with the side's
  // normal and not a made-up one.
  auto hit = scene.hit({0, 0.9999, 5}, {0, 0, -1});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 5.0 - 0.00005, 1e-6);
  expect_near(hit->normal, Vec3(0, 1, 2) / std::sqrt(5.0), 1e-6, "near the apex");
  // Just above the apex, and beside the tip: nothing.
  EXPECT_FALSE(scene.hit({0, 1.0001, 5}, {0, 0, -1}));
  EXPECT_FALSE(scene.hit({0.0001, 0.9999, 5}, {0, 0, -1}));
  EXPECT_TRUE(scene.hit({0.00004, 0.9999, 5}, {0, 0, -1}));
  // Straight down beside the apex: through the upper nappe of the double cone, which is
  // no part of the solid, then into the cone where it is 0.01 wide.
  hit = scene.hit({0.01, 3, 0}, {0, -1, 0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->position.y, 1 - 0.02, 1e-7);
  expect_near(hit->normal, Vec3(2, 1, 0) / std::sqrt(5.0), 1e-9, "beside the apex");
  // Across the upper nappe alone.
  EXPECT_FALSE(scene.hit({0, 1.5, 5}, {0, 0, -1}));
  EXPECT_FALSE(scene.hit({0, 3, 5}, {0, -1.5, -10}));
}

TEST(QuadricGeometryTest, RaysParallelToTheConesSide) {
  // Radius 1 and height 1: the side slopes at 45°, and (0, -1, -1) runs along its far
  // generator (the quadratic's leading coefficient is exactly 0). The apex is at y = 0.5.
  const OneObject scene(cone({0, 0, 0}, 1, 1));
  // From (0, 1.5, 2): onto the near side at (0, 0, 0.5), head on.
  auto hit = scene.hit({0, 1.5, 2}, {0, -1, -1});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 1.5 * std::sqrt(2.0), 1e-6);
  expect_near(hit->normal, Vec3(0, 1, 1) / std::sqrt(2.0), 1e-9, "parallel entry");
  expect_near(hit->position, {0, 0, 0.5}, 1e-6, "parallel entry");
  // Onward from there the ray stays beside the far side and leaves by the base.
  hit = scene.hit({0, 0, 0.4}, {0, -1, -1});
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->normal, Vec3(0, -1, 0));
  expect_near(hit->position, {0, -0.5, -0.1}, 1e-6, "parallel exit");
  // The same line through the upper nappe only: it crosses y = 0.5 outside the cone.
  EXPECT_FALSE(scene.hit({0, 2.5, 1.5}, {0, -1, -1}));
}

// Every hit of rays straight at points of the surface: from 3 units out along the world
// normal, and from a point inside out through it.
struct SurfacePoint {
  Vec3 object_point;
  Vec3 object_normal;  // outward, any length
};

void expect_hits_through(const json& object, const Vec3& object_inside,
                         std::initializer_list<SurfacePoint> points) {
  const OneObject scene(object);
  const Mat4& m = scene.renderer.scene().objects[0].transform;
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(m)));
  const Vec3 inside(m * glm::dvec4(object_inside, 1.0));
  RayPacket packet;
  int lane = 0;
  for (const SurfacePoint& surface : points) {
    SCOPED_TRACE("object point (" + std::to_string(surface.object_point.x) + ", " +
                 std::to_string(surface.object_point.y) + ", " +
                 std::to_string(surface.object_point.z) + ")");
    const Vec3 point(m * glm::dvec4(surface.object_point, 1.0));
    const Vec3 n = glm::normalize(normal_matrix * surface.object_normal);
    const Ray in{glm::vec3(point + 3.0 * n), glm::vec3(-n)};
    const auto hit = scene.geometry().intersect(in, kInfinity);
    ASSERT_TRUE(hit.has_value());
    EXPECT_NEAR(hit->t, 3.0, 1e-5);
    expect_near(hit->normal, n, 1e-5, "normal from outside");
    expect_near(hit->position, point, 1e-5, "point from outside");
    EXPECT_FALSE(scene.geometry().occluded(in, 2.9f));
    EXPECT_TRUE(scene.geometry().occluded(in, 3.1f));
    const Ray out{glm::vec3(inside), glm::vec3(glm::normalize(point - inside))};
    const auto exit = scene.geometry().intersect(out, kInfinity);
    ASSERT_TRUE(exit.has_value());
    EXPECT_NEAR(exit->t, glm::length(point - inside), 1e-5);
    expect_near(exit->normal, n, 1e-5, "normal from inside");
    EXPECT_FALSE(scene.geometry().intersect(Ray{in.origin, -in.direction}, kInfinity));
    packet.active[lane] = true;
    packet.set(lane++, in);
  }
  SurfaceHit hits[kPacketSize];
  bool found[kPacketSize];
  scene.geometry().intersect(packet, hits, found);
  for (int i = 0; i < lane; ++i) {
    ASSERT_TRUE(found[i]) << "lane " << i;
    const auto single = scene.geometry().intersect(packet.ray(i), kInfinity);
    EXPECT_EQ(hits[i].t, single->t) << "lane " << i;
    EXPECT_EQ(hits[i].position, single->position) << "lane " << i;
    EXPECT_EQ(hits[i].normal, single->normal) << "lane " << i;
  }
}

TEST(QuadricGeometryTest, UnderTransformsHitsAreWhereTheTransformPutsThem) {
  // A rotation, a scale along other axes than the shape's, a mirror and a move.
  const json transforms[3] = {
      {{{"rotate", {{"axis", {0, 0, 1}}, {"degrees", 90}}}}, {{"translate", {1, -1, 2}}}},
      {{{"rotate", {{"axis", {1, 1, 1}}, {"degrees", 40}}}},
       {{"scale", {1, 3, 0.5}}},
       {{"translate", {-2, 0, 1}}}},
      {{{"scale", {-1, 2, 1}}}, {{"rotate", {{"axis", {1, 0, 0}}, {"degrees", -25}}}}}};
  const double s = std::sqrt(0.5);
  for (const json& steps : transforms) {
    SCOPED_TRACE(steps.dump());
    json object = cylinder({1, 2, 3}, 0.5, 2);
    object["transform"] = steps;
    expect_hits_through(object, {1, 2, 3},
                        {{{1.5, 2, 3}, {1, 0, 0}},
                         {{1, 2.5, 2.5}, {0, 0, -1}},
                         {{1 + 0.5 * s, 1.2, 3 + 0.5 * s}, {1, 0, 1}},
                         {{1.2, 3, 3.1}, {0, 1, 0}},
                         {{0.9, 1, 2.8}, {0, -1, 0}}});
    // Radius 1, height 2 around (1, 2, 3): the apex at y = 3, the base at y = 1, and at
    // y = 2 the radius is 0.5.
    object = cone({1, 2, 3}, 1, 2);
    object["transform"] = steps;
    expect_hits_through(object, {1, 1.5, 3},
                        {{{1.5, 2, 3}, {2, 1, 0}},
                         {{1, 2, 2.5}, {0, 1, -2}},
                         {{1 - 0.75 * s, 1.5, 3 - 0.75 * s}, {-2 * s, 1, -2 * s}},
                         {{1.3, 1, 2.6}, {0, -1, 0}}});
  }
}

// Snell's law as the tracer has it, for the unit direction d and the unit normal n facing it.
Vec3 refract(const Vec3& d, const Vec3& n, double eta) {
  const double cos_i = glm::dot(-d, n);
  const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
  EXPECT_LE(sin2_t, 1.0) << "total internal reflection";
  return eta * d + (eta * cos_i - std::sqrt(1.0 - sin2_t)) * n;
}

// Behind a clear solid, a small lamp where a ray refracted in and out of it goes: the pixel
// sees the lamp only if the solid bends the ray in and out as Snell's law says.
void expect_refracted_onto_lamp(json solid, const Vec3& eye, const Vec3& towards,
                                const Vec3& entry_point, const Vec3& entry_normal,
                                const Vec3& exit_point, const Vec3& exit_normal) {
  const double ior = 1.5;
  const Vec3 d0 = glm::normalize(towards - eye);
  const Vec3 d1 = refract(d0, entry_normal, 1.0 / ior);
  ASSERT_NEAR(glm::length(glm::cross(glm::normalize(exit_point - entry_point), d1)), 0.0, 1e-9)
      << "the test's own path";
  const Vec3 d2 = refract(d1, -exit_normal, ior);
  const Vec3 lamp = exit_point + 10.0 * d2;
  json scene = pinhole_scene(eye, towards, std::fabs(d0.y) > 0.9 ? Vec3(0, 0, -1) : Vec3(0, 1, 0));
  solid["material"] = {{"ambient", 0}, {"diffuse", 0}, {"transmission", 1}, {"ior", ior}};
  scene["objects"] = {solid,
                      {{"type", "sphere"},
                       {"center", {lamp.x, lamp.y, lamp.z}},
                       {"radius", 0.3},
                       {"material", {{"ambient", 0}, {"diffuse", 0}, {"emission", 0.75}}}}};
  EXPECT_EQ(render_pixel(scene).r, 0.75);
  // The unbent ray, as through a thin surface, passes the lamp by.
  const Vec3 unbent = exit_point + 10.0 * d0;
  EXPECT_GT(glm::length(unbent - lamp), 1.0);
}

TEST(QuadricGeometryTest, RaysRefractInAndOutOfTheSolids) {
  // A cylinder of radius 1 on the y axis, met along -z at x = 0.5: the ray bends towards
  // the axis, crosses a chord of 2·cos θt and leaves where the chord ends.
  const double sin_i = 0.5;
  const double theta_i = std::asin(sin_i);
  const double theta_t = std::asin(sin_i / 1.5);
  const Vec3 entry(0.5, 0, std::cos(theta_i));
  const double exit_angle = theta_i + (M_PI - 2 * theta_t);  // from +z towards +x
  const Vec3 exit(std::sin(exit_angle), 0, std::cos(exit_angle));
  expect_refracted_onto_lamp(cylinder({0, 0, 0}, 1, 4), {0.5, 0, 10}, {0.5, 0, 0}, entry, entry,
                             exit, exit);
  // A cone of radius 2 and height 1 with its base at y = 0, met straight up through the
  // base at x = 0.5: unbent there, then out through the side at y = 0.75 (radius 0.5),
  // whose normal is (1, 2) / √5 across the axis.
  expect_refracted_onto_lamp(cone({0, 0.5, 0}, 2, 1), {0.5, -10, 0}, {0.5, 0, 0}, {0.5, 0, 0},
                             {0, -1, 0}, {0.5, 0.75, 0}, Vec3(1, 2, 0) / std::sqrt(5.0));
}

// Secondary rays from hits all over a shape, near the origin or far from it, small or
// large: a ray leaving outwards meets nothing (the shape is convex and alone), and one
// going on inwards meets nothing but the far side, from inside. It may miss that too where
// the far side is nearer than the offset that moves its origin off the surface (a few
// hundred units in the last place of the coordinates: far from the origin, most of a small
// shape), as a ray near the rim or the apex does.
void expect_no_self_intersection(json object, const Vec3& centre, double size) {
  object["center"] = {centre.x, centre.y, centre.z};
  object["radius"] = size;
  object["height"] = 1.5 * size;
  SCOPED_TRACE(object.dump());
  const OneObject scene(object);
  const Vec3 eye = centre + size * Vec3(1.2, 1.5, 3);
  int hits = 0;
  int wrong = 0;
  int far_sides = 0;
  for (int i = 0; i < 24; ++i)
    for (int j = 0; j < 24; ++j) {
      const Vec3 target = centre + size * Vec3(-1 + i / 11.5, -1 + j / 11.5, 0);
      const Ray ray{glm::vec3(eye), glm::vec3(glm::normalize(target - eye))};
      const auto hit = scene.geometry().intersect(ray, kInfinity);
      if (!hit) continue;
      ++hits;
      const Vec3 d(ray.direction);
      const Vec3 mirrored = d - 2.0 * glm::dot(d, hit->normal) * hit->normal;
      wrong += scene.geometry().intersect(ray_from(*hit, mirrored), kInfinity).has_value();
      wrong += scene.geometry().occluded(ray_from(*hit, hit->normal), kInfinity);
      const auto far_side = scene.geometry().intersect(ray_from(*hit, d), kInfinity);
      if (!far_side) continue;
      ++far_sides;
      wrong += glm::dot(far_side->normal, d) <= 0.0;
    }
  EXPECT_GT(hits, 250);
  EXPECT_EQ(wrong, 0) << "of " << hits << " hits";
  EXPECT_GT(far_sides, hits * 4 / 5);
}

TEST(QuadricGeometryTest, NoSelfIntersectionNearOrFarSmallOrLarge) {
  for (const auto& [centre, size] :
       {std::pair{Vec3(0, 0, 0), 1.0}, std::pair{Vec3(1e5, -2e5, 3e5), 10.0},
        std::pair{Vec3(0, 0, 0), 1e4}, std::pair{Vec3(2, 1, 0), 1e-3}}) {
    expect_no_self_intersection(cylinder({0, 0, 0}, 1, 1), centre, size);
    expect_no_self_intersection(cone({0, 0, 0}, 1, 1), centre, size);
  }
}

}  // namespace
}  // namespace tessera
