// Each term of I = I_E + K_A·I_A + Σ_L (K_D·(N·L) + K_S·(V·R)^n)·S_L·I_L + K_R·I_R + K_T·I_T,
// checked at one pixel against a value worked out by hand from the scene's geometry.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>

#include <gtest/gtest.h>

#include "tests/unit/worker/render_helpers.hpp"

namespace tessera {
namespace {

using test::json;
using test::pinhole_scene;
using test::render_pixel;

constexpr double kTolerance = 1e-5;

void expect_color(const Color& actual, const Color& expected) {
  EXPECT_NEAR(actual.r, expected.r, kTolerance);
  EXPECT_NEAR(actual.g, expected.g, kTolerance);
  EXPECT_NEAR(actual.b, expected.b, kTolerance);
}

const json kBlack = {{"ambient", 0}, {"diffuse", 0}, {"specular", 0}};
json emitter(double e) { return {{"ambient", 0}, {"diffuse", 0}, {"emission", e}}; }
json matte(double kd, double ka = 0) { return {{"ambient", ka}, {"diffuse", kd}}; }
json floor_plane(const json& material) {
  return {{"type", "plane"}, {"point", {0, 0, 0}}, {"normal", {0, 1, 0}}, {"material", material}};
}
json sphere(const Vec3& c, double r, const json& material) {
  return {{"type", "sphere"}, {"center", {c.x, c.y, c.z}}, {"radius", r}, {"material", material}};
}
// Looking straight down at the floor's origin: N = V = +y.
json looking_down(const Vec3& at = {0, 0, 0}) {
  return pinhole_scene(at + Vec3(0, 5, 0), at, {0, 0, -1});
}

TEST(ShadingTest, AmbientAndEmissionOnly) {
  json scene = pinhole_scene({0, 0, 5}, {0, 0, 0});
  scene["ambient_light"] = {0.5, 0.25, 1.0};
  scene["objects"].push_back(
      sphere({0, 0, 0}, 1,
             {{"ambient", {0.2, 0.4, 0.6}}, {"diffuse", 0.9}, {"emission", {0.01, 0.02, 0.03}}}));
  expect_color(render_pixel(scene), {0.01 + 0.1, 0.02 + 0.1, 0.03 + 0.6});
}

TEST(ShadingTest, AHitThatSendsNoRayOnTakesItsCheckerCellsEmissionAndAmbient) {
  // With no lights and no bounce left, a hit's colour is I_E + K_A·I_A alone, worked out by
  // a shorter path than a hit that sends rays on: it must still follow the checkerboard,
  // and give every pixel the bits the full path gives it.
  json scene = pinhole_scene({0.3, 4, 0.2}, {0, 0, 0}, {0, 0, -1});
  scene["image"] = {{"width", 24}, {"height", 24}};
  scene["camera"]["fov_y"] = 60;
  scene["ambient_light"] = {0.5, 0.25, 1.0};
  scene["render"]["max_depth"] = 0;
  scene["objects"].push_back(floor_plane({{"ambient", {0.2, 0.4, 0.6}},
                                          {"emission", {0.01, 0.02, 0.03}},
                                          {"reflection", 0},
                                          {"checker", {{"size", 1}, {"ambient", 0.8}}}}));
  const Image shortcut = test::render_image(scene, 1);
  const Color even(0.01 + 0.5 * 0.2, 0.02 + 0.25 * 0.4, 0.03 + 1.0 * 0.6);
  const Color odd(0.01 + 0.5 * 0.8, 0.02 + 0.25 * 0.8, 0.03 + 1.0 * 0.8);
  int evens = 0;
  int odds = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) {
      const float* pixel = shortcut.pixel(x, y);
      const Color value(pixel[0], pixel[1], pixel[2]);
      const bool is_even = glm::all(glm::lessThan(glm::abs(value - even), Color(kTolerance)));
      const bool is_odd = glm::all(glm::lessThan(glm::abs(value - odd), Color(kTolerance)));
      EXPECT_TRUE(is_even || is_odd) << "pixel " << x << ", " << y;
      evens += is_even;
      odds += is_odd;
    }
  EXPECT_GT(evens, 24);
  EXPECT_GT(odds, 24);
  // One bounce left: each hit now takes the full path, and sends a reflected ray that adds
  // nothing (K_R = 0).
  scene["render"]["max_depth"] = 1;
  const Image full = test::render_image(scene, 1);
  EXPECT_EQ(
      std::memcmp(full.pixels().data(), shortcut.pixels().data(), shortcut.pixels().size_bytes()),
      0);
}

TEST(ShadingTest, MissShowsTheBackground) {
  json scene = pinhole_scene({0, 0, 5}, {0, 0, 0});
  scene["background"] = {0.1, 0.2, 0.3};
  expect_color(render_pixel(scene), {0.1, 0.2, 0.3});
}

TEST(ShadingTest, DiffuseUnderDirectionalLight) {
  json scene = looking_down();
  scene["objects"].push_back(floor_plane(matte(0.6)));
  scene["lights"].push_back(
      {{"type", "directional"}, {"direction", {0, -1, -1}}, {"intensity", {1.0, 0.5, 0.25}}});
  // N·L = cos 45°.
  const double n_dot_l = 1.0 / std::sqrt(2.0);
  expect_color(render_pixel(scene), 0.6 * n_dot_l * Color(1.0, 0.5, 0.25));

  scene["lights"][0]["direction"] = {0, 1, 0};  // from below: behind the surface
  expect_color(render_pixel(scene), {0, 0, 0});
}

TEST(ShadingTest, PointLightAttenuationByEachCoefficient) {
  // Light 3 units straight above the lit point: d = 3, N·L = 1.
  const struct {
    double kc, kl, kq, denominator;
  } cases[] = {{2, 0, 0, 2}, {0, 0.5, 0, 1.5}, {0, 0, 0.25, 2.25}, {1, 1, 1, 13}};
  for (const auto& c : cases) {
    json scene = looking_down();
    scene["objects"].push_back(floor_plane(matte(0.6)));
    scene["lights"].push_back({{"type", "point"},
                               {"position", {0, 3, 0}},
                               {"intensity", 1},
                               {"attenuation", {c.kc, c.kl, c.kq}}});
    expect_color(render_pixel(scene), Color(0.6 / c.denominator));
  }
}

TEST(ShadingTest, SpotConeEdgeAndExponent) {
  // Spot at (0,4,0) pointing down; lit point (1,0,0): D·L' = N·L = 4/√17 (angle 14.04°).
  const double cos_angle = 4.0 / std::sqrt(17.0);
  auto scene_with = [](double cutoff, double exponent) {
    json scene = looking_down({1, 0, 0});
    scene["objects"].push_back(floor_plane(matte(0.6)));
    json spot = {{"type", "spot"},
                 {"position", {0, 4, 0}},
                 {"direction", {0, -1, 0}},
                 {"intensity", 1},
                 {"attenuation", {1, 0, 0}}};
    if (cutoff > 0) spot["cutoff"] = cutoff;
    if (exponent >= 0) spot["exponent"] = exponent;
    scene["lights"].push_back(spot);
    return scene;
  };
  expect_color(render_pixel(scene_with(15, 3)), Color(0.6 * std::pow(cos_angle, 3) * cos_angle));
  expect_color(render_pixel(scene_with(14, 3)), Color(0.0));  // just outside the cone
  // Defaults (cutoff 90, exponent 1): I_0 (D·L') / attenuation.
  expect_color(render_pixel(scene_with(-1, -1)), Color(0.6 * cos_angle * cos_angle));
}

TEST(ShadingTest, SpecularHighlightExponent) {
  // L at 30° from N in the x-y plane: R = (-sin 30°, cos 30°, 0), V = N, so V·R = cos 30°.
  const double v_dot_r = std::cos(std::numbers::pi / 6);
  for (double n : {1.0, 10.0, 50.0}) {
    json scene = looking_down();
    scene["objects"].push_back(floor_plane(
        {{"ambient", 0}, {"diffuse", 0}, {"specular", 0.5}, {"shininess", n}, {"reflection", 0}}));
    scene["lights"].push_back(
        {{"type", "directional"}, {"direction", {-0.5, -v_dot_r, 0}}, {"intensity", 2}});
    expect_color(render_pixel(scene), Color(0.5 * std::pow(v_dot_r, n) * 2));
  }
}

// The floor at the origin seen from the side, lit from straight above, with a blocker
// between the point and the light that the camera ray does not pass.
json shadow_scene(const json& blocker) {
  json scene = pinhole_scene({3, 1, 0}, {0, 0, 0});
  scene["ambient_light"] = 1;
  scene["objects"].push_back(floor_plane(matte(0.6, 0.1)));
  scene["lights"].push_back({{"type", "directional"}, {"direction", {0, -1, 0}}, {"intensity", 1}});
  if (!blocker.is_null()) scene["objects"].push_back(blocker);
  return scene;
}

TEST(ShadingTest, ShadowsFromOpaqueAndTransmissiveOccluders) {
  expect_color(render_pixel(shadow_scene(nullptr)), Color(0.1 + 0.6));
  expect_color(render_pixel(shadow_scene(sphere({0, 2, 0}, 0.5, matte(0.5)))), Color(0.1));
  // A solid glass sphere: the shadow ray crosses two surfaces, each passing K_T.
  const json glass = {{"diffuse", 0}, {"transmission", {1.0, 0.5, 0.0}}, {"ior", 1.5}};
  expect_color(render_pixel(shadow_scene(sphere({0, 2, 0}, 0.5, glass))),
               Color(0.1) + 0.6 * Color(1.0, 0.25, 0.0));
  // A thin pane: one surface.
  const json pane = {{"type", "triangle"},
                     {"vertices", {{-1, 2, -1}, {1, 2, -1}, {0, 2, 1}}},
                     {"material", {{"transmission", 0.5}}}};
  expect_color(render_pixel(shadow_scene(pane)), Color(0.1 + 0.6 * 0.5));
}

TEST(ShadingTest, ShadowRaysWalkThroughEveryTransmissiveObjectOnTheirWay) {
  // Two glass spheres and a glass box one above another over the shaded point: the walk goes
  // on after leaving each of them, and each surface passes its K_T.
  const json tinted = {{"diffuse", 0}, {"transmission", {1.0, 0.5, 0.8}}, {"ior", 1.5}};
  const json clear = {{"diffuse", 0}, {"transmission", 0.9}, {"ior", 1.3}};
  json scene = shadow_scene(sphere({0, 2, 0}, 0.5, tinted));
  scene["objects"].push_back(sphere({0, 3.5, 0}, 0.5, clear));
  scene["objects"].push_back(
      {{"type", "box"}, {"min", {-0.5, 5, -0.5}}, {"max", {0.5, 6, 0.5}}, {"material", clear}});
  const Color through = Color(1.0, 0.25, 0.64) * (0.9 * 0.9) * (0.9 * 0.9);
  expect_color(render_pixel(scene), Color(0.1) + 0.6 * through);
  // Past eight transmissive objects the tracer tests one box around them all, not a box
  // each; these ten more lie off the shadow ray's way.
  for (int k = 0; k < 10; ++k) scene["objects"].push_back(sphere({5.0 + 2 * k, 2, 5}, 0.5, clear));
  expect_color(render_pixel(scene), Color(0.1) + 0.6 * through);
}

TEST(ShadingTest, AShadowRayLeavingTheLastGlassOnItsWayStopsWalking) {
  // Shadow rays: one query for anything opaque, then one per transmissive surface crossed.
  // Leaving a sphere, the ray can never meet it again, and no other transmissive object's
  // box lies ahead: the walk ends without asking Embree for the nothing that is there.
  const json glass = {{"diffuse", 0}, {"transmission", 0.5}, {"ior", 1.5}};
  json scene = shadow_scene(sphere({0, 2, 0}, 0.5, glass));
  const auto shadow_rays = [&] {
    const Renderer renderer(parse_scene(scene));
    float rgb[3];
    const std::uint64_t in_packets = renderer.render_tile({0, 0, 1, 1}, rgb).shadow;
    RayCounts single;
    renderer.tracer().trace(renderer.camera().ray_through(0.5, 0.5), 0, single);
    EXPECT_EQ(single.shadow, in_packets);
    return in_packets;
  };
  EXPECT_EQ(shadow_rays(), 3u);
  // A second sphere above the first: the walk goes on after leaving the first.
  scene["objects"].push_back(sphere({0, 3.5, 0}, 0.5, glass));
  EXPECT_EQ(shadow_rays(), 5u);
}

TEST(ShadingTest, MirrorReflectionAndDepthZero) {
  // The camera looks at the mirror floor at 45°; the mirror ray goes up at 45° into an
  // emitting sphere.
  json scene = pinhole_scene({0, 1, 1}, {0, 0, 0});
  scene["objects"].push_back(floor_plane({{"ambient", 0}, {"diffuse", 0}, {"reflection", 0.8}}));
  scene["objects"].push_back(sphere({0, 5, -5}, 1, emitter(0.5)));
  expect_color(render_pixel(scene), Color(0.8 * 0.5));
  scene["render"]["max_depth"] = 0;
  expect_color(render_pixel(scene), Color(0.0));
}

TEST(ShadingTest, MaxDepthCutsOffBetweenParallelMirrors) {
  // Two facing mirrors that each emit 0.1 and reflect half: the ray bounces forever, so
  // with depth D the pixel is 0.1 · (1 + 1/2 + ... + 1/2^D).
  for (int depth : {0, 1, 2, 5}) {
    json scene = pinhole_scene({0, 0, 0}, {1, 0, 0});
    const json mirror = {{"ambient", 0}, {"diffuse", 0}, {"emission", 0.1}, {"reflection", 0.5}};
    scene["objects"].push_back(
        {{"type", "plane"}, {"point", {1, 0, 0}}, {"normal", {-1, 0, 0}}, {"material", mirror}});
    scene["objects"].push_back(
        {{"type", "plane"}, {"point", {-1, 0, 0}}, {"normal", {1, 0, 0}}, {"material", mirror}});
    scene["render"]["max_depth"] = depth;
    double expected = 0;
    for (int k = 0; k <= depth; ++k) expected += 0.1 * std::pow(0.5, k);
    expect_color(render_pixel(scene), Color(expected));
  }
}

const json glass(double kt, double ior) {
  return {{"ambient", 0}, {"diffuse", 0}, {"transmission", kt}, {"ior", ior}};
}

TEST(ShadingTest, RefractionThroughAGlassSlabShiftsTheRay) {
  // A slab 1 thick (z from -0.5 to 0.5), hit at 45°: inside, sin θt = sin 45° / 1.5, and
  // the ray leaves parallel to itself, shifted. A small emitter sits on the shifted line.
  const Vec3 d = glm::normalize(Vec3(1, 0, -1));
  const Vec3 entry(0, 0.3, 0.5);
  const double tan_t = std::tan(std::asin(std::sin(std::numbers::pi / 4) / 1.5));
  const Vec3 exit(tan_t, 0.3, -0.5);
  const Vec3 target = exit + 3.0 * d;  // 0.33 off the unbent line, radius 0.1
  for (double ior : {1.5, 1.0}) {
    json scene = pinhole_scene(entry - 5.0 * d, entry);
    scene["objects"].push_back({{"type", "box"},
                                {"min", {-10, -10, -0.5}},
                                {"max", {10, 10, 0.5}},
                                {"material", glass(0.8, ior)}});
    scene["objects"].push_back(sphere(target, 0.1, emitter(1)));
    // Two surfaces crossed, K_T each; without bending (ior 1) the ray misses.
    expect_color(render_pixel(scene), Color(ior == 1.5 ? 0.64 : 0.0));
  }
}

TEST(ShadingTest, RefractionThroughAGlassSphere) {
  // A ray parallel to the axis at height h = 0.5 through a unit ball of ior 1.5: it enters
  // at θ1 = asin h, bends to θ2 = asin(h/1.5), leaves at polar angle θ1 + π - 2θ2, turned
  // towards the axis by 2(θ1 - θ2).
  const double t1 = std::asin(0.5);
  const double t2 = std::asin(0.5 / 1.5);
  const double exit_angle = t1 + std::numbers::pi - 2 * t2;
  const double deviation = 2 * (t1 - t2);
  const Vec3 exit(0, std::sin(exit_angle), std::cos(exit_angle));
  const Vec3 out(0, -std::sin(deviation), -std::cos(deviation));
  json scene = pinhole_scene({0, 0.5, 10}, {0, 0.5, 0});
  scene["objects"].push_back(sphere({0, 0, 0}, 1, glass(0.9, 1.5)));
  scene["objects"].push_back(sphere(exit + 3.0 * out, 0.05, emitter(1)));
  expect_color(render_pixel(scene), Color(0.9 * 0.9));
}

// A right-angle glass prism: the ray enters a leg face head-on, meets the hypotenuse at
// 45° and, beyond the critical angle, is totally reflected out through the other leg.
json prism_scene(double ior) {
  json scene = pinhole_scene({0.5, 0.5, -5}, {0.5, 0.5, 0});
  scene["objects"].push_back(
      {{"type", "mesh"},
       {"positions", {{0, 0, 0}, {2, 0, 0}, {0, 0, 2}, {0, 1, 0}, {2, 1, 0}, {0, 1, 2}}},
       {"triangles",
        {{0, 1, 2}, {3, 5, 4}, {0, 3, 4}, {0, 4, 1}, {0, 2, 5}, {0, 5, 3}, {1, 4, 5}, {1, 5, 2}}},
       {"material", glass(0.9, ior)}});
  scene["objects"].push_back(sphere({-3, 0.5, 1.5}, 0.2, emitter(1)));
  return scene;
}

TEST(ShadingTest, TotalInternalReflectionFollowsTheMirrorDirection) {
  // Critical angle for ior 1.5 is 41.8° < 45°: three K_T on the way to the emitter.
  expect_color(render_pixel(prism_scene(1.5)), Color(0.9 * 0.9 * 0.9));
  // For ior 1.2 (critical angle 56.4°) the ray refracts out of the hypotenuse instead.
  expect_color(render_pixel(prism_scene(1.2)), Color(0.0));
}

TEST(ShadingTest, ThinSurfaceLetsTheRayPassUnbent) {
  json scene = pinhole_scene({0, 0, 5}, {0, 0, 0});
  scene["objects"].push_back({{"type", "plane"},
                              {"point", {0, 0, 0}},
                              {"normal", {1, 0, 1}},
                              {"material", glass(0.5, 1.5)}});
  scene["objects"].push_back(sphere({0, 0, -3}, 0.2, emitter(1)));
  expect_color(render_pixel(scene), Color(0.5));
}

}  // namespace
}  // namespace tessera
