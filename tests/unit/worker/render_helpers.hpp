// Small helpers shared by the renderer tests.
#pragma once

#include <nlohmann/json.hpp>

#include "common/image.hpp"
#include "common/scene_parser.hpp"
#include "worker/local_render.hpp"
#include "worker/renderer.hpp"

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
