// Small helpers shared by the renderer tests.
#pragma once

#include <cmath>

#include <nlohmann/json.hpp>

#include "common/image/image.hpp"
#include "common/scene/scene_parser.hpp"
#include "tracer/local_render.hpp"
#include "tracer/renderer.hpp"

namespace tessera::test {

using nlohmann::json;

// A 1×1 image whose one pixel's ray runs exactly from `eye` through `look_at`; no lights,
// no ambient light, black background. Tests add what they measure.
inline json pinhole_scene(const Vec3& eye, const Vec3& look_at, const Vec3& up = {0, 1, 0}) {
  return {{"image", {{"width", 1}, {"height", 1}}},
          {"camera",
           {{"eye", {eye.x, eye.y, eye.z}},
            {"look_at", {look_at.x, look_at.y, look_at.z}},
            {"up", {up.x, up.y, up.z}}}},
          {"background", 0},
          {"ambient_light", 0},
          {"lights", json::array()},
          {"objects", json::array()}};
}

// Every feature and every shape at once, with several samples per pixel.
inline json busy_scene() {
  return {
      {"image", {{"width", 67}, {"height", 45}}},
      {"camera", {{"eye", {0, 2, 7}}, {"look_at", {0, 0.8, 0}}, {"fov_y", 40}}},
      {"render", {{"samples_per_pixel", 4}, {"max_depth", 6}}},
      {"background", {0.3, 0.4, 0.6}},
      {"materials",
       {{"floor", {{"checker", {{"size", 0.7}, {"diffuse", 0.1}}}}},
        {"mirror", {{"diffuse", 0.1}, {"specular", 0.8}, {"shininess", 80}}},
        {"glass",
         {{"diffuse", 0},
          {"ambient", 0},
          {"transmission", 0.9},
          {"ior", 1.5},
          {"specular", 0.1},
          {"shininess", 100}}}}},
      {"lights",
       {{{"type", "point"}, {"position", {3, 5, 4}}, {"attenuation", {1, 0.02, 0.005}}},
        {{"type", "spot"},
         {"position", {-3, 4, 2}},
         {"direction", {1, -1, -0.5}},
         {"cutoff", 30},
         {"exponent", 4}},
        {{"type", "directional"}, {"direction", {0.2, -1, -0.3}}, {"intensity", 0.3}}}},
      {"objects",
       {{{"type", "plane"}, {"point", {0, 0, 0}}, {"normal", {0, 1, 0}}, {"material", "floor"}},
        {{"type", "sphere"}, {"center", {-1.2, 1, 0}}, {"radius", 1}, {"material", "mirror"}},
        {{"type", "sphere"}, {"center", {1.2, 0.8, 0.5}}, {"radius", 0.8}, {"material", "glass"}},
        {{"type", "box"},
         {"min", {-0.4, 0, -2}},
         {"max", {0.4, 1.5, -1.2}},
         {"transform", {{{"rotate", {{"axis", {0, 1, 0}}, {"degrees", 30}}}}}}},
        // Cylinders and cones, tilted and squashed: glass that bends and reflects rays
        // inside it, a mirror, and a diffuse one whose shadow falls through the glass.
        {{"type", "cylinder"},
         {"center", {0, 0, 0}},
         {"radius", 0.45},
         {"height", 1.2},
         {"material", "glass"},
         {"transform",
          {{{"rotate", {{"axis", {0, 0, 1}}, {"degrees", 25}}}},
           {{"translate", {2.5, 0.7, -0.6}}}}}},
        {{"type", "cone"},
         {"center", {-2.6, 0.75, -0.5}},
         {"radius", 0.6},
         {"height", 1.5},
         {"material", "mirror"},
         {"transform", {{{"scale", {1, 1, 0.7}}}}}},
        {{"type", "cylinder"}, {"center", {0.2, 0.25, 1.8}}, {"radius", 0.3}, {"height", 0.5}},
        {{"type", "cone"},
         {"center", {0, 0, 0}},
         {"radius", 0.4},
         {"height", 0.9},
         {"material", "glass"},
         {"transform",
          {{{"rotate", {{"axis", {1, 0, 0}}, {"degrees", 100}}}},
           {{"translate", {-1, 0.4, 1.6}}}}}}}}};
}

// An inline torus around y of 2·rings·sides triangles, big enough for a BVH of its own
// (tracer/mesh_bvh.hpp), with smooth normals or flat.
inline json torus(int rings, int sides, double major, double minor, bool smooth) {
  constexpr double pi = 3.14159265358979323846;
  json positions = json::array();
  json normals = json::array();
  json triangles = json::array();
  for (int r = 0; r < rings; ++r) {
    const double a = 2 * pi * r / rings;
    for (int s = 0; s < sides; ++s) {
      const double b = 2 * pi * s / sides;
      const double out = major + minor * std::cos(b);
      positions.push_back({out * std::cos(a), minor * std::sin(b), out * std::sin(a)});
      normals.push_back({std::cos(b) * std::cos(a), std::sin(b), std::cos(b) * std::sin(a)});
      const int next_r = (r + 1) % rings;
      const int next_s = (s + 1) % sides;
      const int v00 = r * sides + s, v01 = r * sides + next_s;
      const int v10 = next_r * sides + s, v11 = next_r * sides + next_s;
      triangles.push_back({v00, v01, v11});
      triangles.push_back({v00, v11, v10});
    }
  }
  json mesh = {{"type", "mesh"}, {"positions", positions}, {"triangles", triangles}};
  if (smooth) mesh["normals"] = normals;
  return mesh;
}

inline Color render_pixel(const json& scene, int x = 0, int y = 0) {
  const Renderer renderer(parse_scene(scene));
  float rgb[3];
  renderer.render_tile({x, y, 1, 1}, rgb);
  return Color(rgb[0], rgb[1], rgb[2]);
}

// `files`: where the scene's mesh files are, if it names any.
inline Image render_image(const json& scene, int threads = 0, int tile_size = 0,
                          const SceneFiles* files = nullptr) {
  const Renderer renderer(parse_scene(scene, Limits{}, nullptr, files));
  return render_local(renderer, threads, tile_size).image;
}

}  // namespace tessera::test
