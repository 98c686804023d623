#include "common/scene/scene_parser.hpp"

#include <cstdint>
#include <limits>
#include <map>
#include <optional>

#include <nlohmann/json.hpp>

#include "common/scene/output_transfer.hpp"
#include "common/scene/scene_parser_parts.hpp"
#include "common/scene/scene_stream.hpp"

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

constexpr auto read_vec3 = [](const ValueReader& v) { return v.vec3(); };

Camera parse_camera(const ValueReader& value) {
  const ObjectReader reader(value);
  reader.allow_only({"eye", "look_at", "up", "fov_y"});
  Camera camera;
  camera.eye = reader.require("eye").animated(read_vec3);
  const ValueReader look_at = reader.require("look_at");
  camera.look_at = look_at.animated(read_vec3);
  camera.up = reader.animated_vec3_or("up", camera.up);
  camera.fov_y_degrees = reader.animated_number_or("fov_y", camera.fov_y_degrees,
                                                   Range::between(0.0, true, 180.0, true));

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

Animation parse_animation(const ObjectReader& root, const Limits& limits) {
  Animation animation;
  const auto found = root.find("animation");
  if (!found) return animation;
  const ObjectReader reader(*found, "an object {\"frames\": [first, last], \"fps\": rate}");
  reader.allow_only({"frames", "fps"});
  animation.animated = true;
  const ValueReader frames = reader.require("frames");
  frames.expect_array_of(2, "an array [first, last] of frame numbers");
  const IntRange frame_range{0, max_frame_number,
                             "frame numbers are at most " + std::to_string(max_frame_number)};
  animation.first = static_cast<int>(frames.element(0).integer(frame_range));
  animation.last = static_cast<int>(frames.element(1).integer(frame_range));
  if (animation.last < animation.first) {
    frames.element(1).fail("must be at least the first frame (" + std::to_string(animation.first) +
                           "), got " + std::to_string(animation.last));
  }
  if (static_cast<std::uint64_t>(animation.frame_count()) > limits.max_frames) {
    frames.fail_limit("must span <= " + std::to_string(limits.max_frames) +
                          " frames (limit max_frames), got " +
                          std::to_string(animation.frame_count()),
                      "max_frames", limits.max_frames);
  }
  animation.fps = reader.number_or("fps", animation.fps, Range::between(0.0, true, 1000.0, false));
  return animation;
}

// The frame a reading reads at: `frame`, or the animation's first.
int frame_to_read(const Animation& animation, std::optional<int> frame) {
  if (!frame) return animation.first;
  if (!animation.contains(*frame)) {
    throw SceneError(animation.animated ? "/animation/frames" : "",
                     "has no frame " + std::to_string(*frame) + ": its frames are " +
                         std::to_string(animation.first) + " to " + std::to_string(animation.last));
  }
  return *frame;
}

// `frame`: the one to read (the first when none); only the reading of the first frame
// checks that every other frame is valid too.
Scene read_scene(const nlohmann::json& document, const Limits& limits, const LiftedArrays* lifted,
                 const ObjectTexts* apart, const SceneFiles* files, std::optional<int> frame) {
  const ObjectReader plain_root(ValueReader(document, "", lifted), "a JSON object");
  // Before the key check: a future version may well have keys this one does not know.
  if (const auto version = plain_root.find("version")) {
    if (version->integer() != 1)
      version->fail("must be 1, the only scene format version, got " + describe(version->json()));
  }
  plain_root.allow_only(scene_keys);

  Scene scene;
  scene.animation = parse_animation(plain_root, limits);
  scene.frame = frame_to_read(scene.animation, frame);
  const FrameReading reading{&scene.animation,  scene.frame, &scene.animation.tracks,
                             limits.max_tracks, nullptr,     !frame.has_value()};
  const ObjectReader root(ValueReader(document, "", lifted, &reading));
  parse_image(root.require("image"), limits, scene);
  scene.camera = read_every_frame(root.require("camera"), parse_camera);
  if (const auto render = root.find("render")) scene.render = parse_render(*render, limits);
  scene.background = root.animated_color_or("background", scene.background);
  scene.ambient_light = root.animated_color_or("ambient_light", scene.ambient_light);

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
  return Limits{most, most, std::numeric_limits<std::uint64_t>::max(),
                most, most, most,
                many, many, many,
                many, many, many};
}

Scene parse_scene(const nlohmann::json& document, const Limits& limits) {
  return parse_scene(document, limits, nullptr);
}

Scene parse_scene(const nlohmann::json& document, const Limits& limits, const LiftedArrays* lifted,
                  const SceneFiles* files) {
  return read_scene(document, limits, lifted, nullptr, files, std::nullopt);
}

Scene parse_scene_frame(const nlohmann::json& document, int frame, const Limits& limits,
                        const LiftedArrays* lifted, const SceneFiles* files) {
  return read_scene(document, limits, lifted, nullptr, files, frame);
}

Scene advance_scene(const nlohmann::json& document, Scene scene, int frame, const Limits& limits,
                    const SceneFiles* files) {
  scene.frame = frame_to_read(scene.animation, frame);
  std::map<std::string, const Track*, std::less<>> known;
  for (const Track& track : scene.animation.tracks) known.emplace(track.pointer, &track);
  const FrameReading reading{&scene.animation, scene.frame, nullptr, 0, &known, false};
  const ObjectReader root(ValueReader(document, "", nullptr, &reading), "a JSON object");
  if (scene.animation.changes(TrackTarget::camera))
    scene.camera = parse_camera(root.require("camera"));
  scene.background = root.animated_color_or("background", Color(0.0));
  scene.ambient_light = root.animated_color_or("ambient_light", Scene{}.ambient_light);
  if (scene.animation.changes(TrackTarget::light))
    scene.lights = parse_lights(root.require("lights"), limits);
  if (scene.animation.changes(TrackTarget::named_material)) {
    MaterialTable named(limits, files);
    named.add_named(root.require("materials"));
    std::vector<Material> read = std::move(named).take();
    std::move(read.begin(), read.end(), scene.materials.begin());
  }
  return scene;
}

Scene check_scene(const nlohmann::json& document, const Limits& limits, const ObjectTexts& objects,
                  const SceneFiles* files) {
  return read_scene(document, limits, nullptr, &objects, files, std::nullopt);
}

}  // namespace tessera
