#include "common/scene_parser.hpp"

#include <cstdint>
#include <limits>

#include <nlohmann/json.hpp>

#include "common/output_transfer.hpp"
#include "common/scene_parser_parts.hpp"
#include "common/scene_stream.hpp"

namespace tessera {
namespace {

// The sine of the angle between view direction and up below which the camera's sideways
// axis, cross(view, up), is too short to normalize reliably.
constexpr double min_up_sine = 1e-6;

void parse_image(const ValueReader& value, const Limits& limits, Scene& scene) {
  const ObjectReader reader(value);
  reader.allow_only({"width", "height"});
  scene.width =
      static_cast<int>(reader.require("width").integer({1, limits.max_width, "limit max_width"}));
  scene.height = static_cast<int>(
      reader.require("height").integer({1, limits.max_height, "limit max_height"}));
  const std::uint64_t pixels = static_cast<std::uint64_t>(scene.width) * scene.height;
  if (pixels > limits.max_pixels)
    value.fail_limit("width x height must be <= " + std::to_string(limits.max_pixels) +
                         " pixels (limit max_pixels), got " + std::to_string(pixels),
                     "max_pixels", limits.max_pixels);
}

Camera parse_camera(const ValueReader& value) {
  const ObjectReader reader(value);
  reader.allow_only({"eye", "look_at", "up", "fov_y"});
  Camera camera;
  camera.eye = reader.require("eye").vec3();
  const ValueReader look_at = reader.require("look_at");
  camera.look_at = look_at.vec3();
  camera.up = reader.vec3_or("up", camera.up);
  camera.fov_y_degrees =
      reader.number_or("fov_y", camera.fov_y_degrees, Range::between(0.0, true, 180.0, true));

  const auto view = try_normalize(camera.look_at - camera.eye);
  if (!view) look_at.fail("must differ from \"eye\"");
  // The pointer names "up" even when it is absent: the default is what needs replacing.
  const std::string up_pointer = reader.pointer() + "/up";
  const auto up = try_normalize(camera.up);
  if (!up) throw SceneError(up_pointer, "must be a non-zero vector, got [0, 0, 0]");
  if (glm::length(glm::cross(*view, *up)) < min_up_sine)
    throw SceneError(up_pointer, "must not be parallel to the view direction (look_at - eye)");
  camera.up = *up;
  return camera;
}

RenderSettings parse_render(const ValueReader& value, const Limits& limits) {
  const ObjectReader reader(value);
  reader.allow_only({"samples_per_pixel", "max_depth", "tile_size", "output_transfer"});
  RenderSettings render;
  render.samples_per_pixel = static_cast<int>(
      reader.integer_or("samples_per_pixel", render.samples_per_pixel,
                        {1, limits.max_samples_per_pixel, "limit max_samples_per_pixel"}));
  render.max_depth = static_cast<int>(
      reader.integer_or("max_depth", render.max_depth, {0, limits.max_depth, "limit max_depth"}));
  render.tile_size = static_cast<int>(reader.integer_or(
      "tile_size", render.tile_size, {1, limits.max_tile_size, "limit max_tile_size"}));
  if (const auto transfer = reader.find("output_transfer")) {
    render.output_transfer = output_transfer_named(transfer->choice(kOutputTransferNames));
  }
  return render;
}

Scene read_scene(const nlohmann::json& document, const Limits& limits, const LiftedArrays* lifted,
                 const ObjectTexts* apart, const SceneFiles* files) {
  const ObjectReader root(ValueReader(document, "", lifted), "a JSON object");
  // Before the key check: a future version may well have keys this one does not know.
  if (const auto version = root.find("version")) {
    if (version->integer() != 1)
      version->fail("must be 1, the only scene format version, got " + describe(version->json()));
  }
  root.allow_only(scene_keys);

  Scene scene;
  parse_image(root.require("image"), limits, scene);
  scene.camera = parse_camera(root.require("camera"));
  if (const auto render = root.find("render")) scene.render = parse_render(*render, limits);
  scene.background = root.color_or("background", scene.background);
  scene.ambient_light = root.color_or("ambient_light", scene.ambient_light);

  MaterialTable materials(limits, files);
  if (const auto named = root.find("materials")) materials.add_named(*named);
  if (const auto lights = root.find("lights")) scene.lights = parse_lights(*lights, limits);
  if (const auto objects = root.find("objects")) {
    const ObjectContext context{limits, files};
    if (apart && objects->json().is_array())
      check_objects(*objects, *apart, materials, context);
    else
      scene.objects = parse_objects(*objects, materials, context);
  }
  scene.materials = std::move(materials).take();
  return scene;
}

}  // namespace

Limits Limits::none() {
  constexpr int most = std::numeric_limits<int>::max();
  constexpr std::size_t many = std::numeric_limits<std::size_t>::max();
  return Limits{most, most, std::numeric_limits<std::uint64_t>::max(), most, most, most, many, many,
                many, many};
}

Scene parse_scene(const nlohmann::json& document, const Limits& limits) {
  return parse_scene(document, limits, nullptr);
}

Scene parse_scene(const nlohmann::json& document, const Limits& limits, const LiftedArrays* lifted,
                  const SceneFiles* files) {
  return read_scene(document, limits, lifted, nullptr, files);
}

Scene check_scene(const nlohmann::json& document, const Limits& limits, const ObjectTexts& objects,
                  const SceneFiles* files) {
  return read_scene(document, limits, nullptr, &objects, files);
}

}  // namespace tessera
