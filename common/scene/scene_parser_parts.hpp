// Internal to the scene parser: the pieces of parse_scene that live in their own files.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/scene/scene.hpp"
#include "common/scene/scene_files.hpp"
#include "common/scene/value_reader.hpp"

namespace tessera {

// --- json_reader.cpp ---

// Scenes need about five levels; anything far deeper is a mistake or an attack, and every
// later walk of the tree (dump, comparison) would recurse that deep.
constexpr int max_json_nesting = 64;

// Throws parse_json_text()'s SceneError for a text nested deeper than max_json_nesting,
// naming the line and column where it goes too deep; returns for any other text.
void check_nesting(std::string_view text);
// parse_json_text()'s SceneError for the syntax error nlohmann's parser reported at
// `position` (the 1-based index of the last character it read) with the message `what`.
SceneError json_syntax_error(std::string_view text, std::size_t position, std::string_view what);

// --- scene_parser.cpp ---

// The keys of a scene's root object; any other is refused.
inline constexpr std::array<std::string_view, 10> scene_keys = {
    "version",       "image",     "camera", "render",  "background",
    "ambient_light", "materials", "lights", "objects", "animation"};

// `read(value)`, which is also read again at every other frame of the animation when the
// first reading records tracks inside it, so that a value that goes wrong only between keys
// (a light's direction through zero, a camera looking at its own eye) is refused at once,
// naming the frame.
template <typename Read>
auto read_every_frame(const ValueReader& value, Read read) -> decltype(read(value)) {
  const FrameReading* frames = value.frames();
  if (frames == nullptr || !frames->every_frame || frames->record == nullptr) return read(value);
  const std::size_t tracks_before = frames->record->size();
  auto result = read(value);
  if (frames->record->size() == tracks_before) return result;
  std::map<std::string, const Track*, std::less<>> known;
  for (std::size_t i = tracks_before; i < frames->record->size(); ++i)
    known.emplace((*frames->record)[i].pointer, &(*frames->record)[i]);
  const Animation& animation = *frames->animation;
  for (int frame = animation.first; frame <= animation.last; ++frame) {
    if (frame == frames->frame) continue;
    const FrameReading at{&animation, frame, nullptr, 0, &known, false};
    try {
      (void)read(value.at(at));
    } catch (const SceneError& error) {
      if (!error.limit().empty()) throw;
      throw SceneError(error.pointer(),
                       "at frame " + std::to_string(frame) + ", " + error.detail());
    }
  }
  return result;
}

// The role of a container that opens at the root, or in a job submission's envelope, in
// the two readers of submitted text (scene_limits_scan.cpp and scene_stream.cpp), whose
// Role enums begin with other, envelope and scene, in that order, and whose frames have a
// `role` and a `key` (the last key read); nothing anywhere else. `scene_member`: the
// envelope's member that holds the scene; nothing when the root is the scene.
template <typename Role, typename Frame>
std::optional<Role> role_in_envelope(const std::vector<Frame>& stack, bool array,
                                     std::optional<std::string_view> scene_member) {
  if (stack.empty()) return array ? Role::other : scene_member ? Role::envelope : Role::scene;
  if (stack.back().role != Role::envelope) return std::nullopt;
  return !array && stack.back().key == *scene_member ? Role::scene : Role::other;
}

// The enumerator whose name `value` holds, `names` listing the enum's names in its order (a
// SceneError at `value` that lists them otherwise).
template <typename Enum, std::size_t N>
Enum enum_choice(const ValueReader& value, const std::string_view (&names)[N]) {
  const std::string_view name = value.choice(names);
  return static_cast<Enum>(std::find(std::begin(names), std::end(names), name) - std::begin(names));
}

// --- material_parser.cpp ---

// `files` locates the textures the material names (none: a texture is refused).
Material parse_material(const ValueReader& value, const SceneFiles* files);
// An asset digest (protocol::AssetDigest): its 64 hex digits, or a SceneError at `value`.
std::string read_digest(const ValueReader& value);

// Scene::materials as it fills up: the default material at 0, then the named ones, then
// the inline ones in the order objects define them.
class MaterialTable {
 public:
  MaterialTable(const Limits& limits, const SceneFiles* files);

  void add_named(const ValueReader& materials);  // the top-level "materials" object
  // An object's "material": a name from "materials" or an inline material object.
  std::uint32_t resolve(const ValueReader& reference);
  // A material a mesh file gives; `where` is the object that names the file.
  std::uint32_t add(Material material, const ValueReader& where);
  std::vector<Material> take() && { return std::move(materials_); }

 private:
  std::size_t max_materials_;
  const SceneFiles* files_;
  std::vector<Material> materials_;
  std::map<std::string, std::uint32_t, std::less<>> by_name_;
};

// --- light_parser.cpp ---

// Each light is checked at every frame (read_every_frame()).
std::vector<Light> parse_lights(const ValueReader& lights, const Limits& limits);

// --- object_parser.cpp ---

// What reading objects needs besides the JSON: the limits, and where mesh files come from
// (none: a mesh file is refused).
struct ObjectContext {
  const Limits& limits;
  const SceneFiles* files = nullptr;
};

std::vector<Object> parse_objects(const ValueReader& objects, MaterialTable& materials,
                                  const ObjectContext& context);

// A mesh object that names a file rather than holding its arrays.
bool is_mesh_file(const ObjectReader& object);
// Appends one Object per part of the file's model to `out`, each with the object's
// "material" if it has one, else the file's own material for the part (added to
// `materials`). `triangles`: those of the objects before it.
void parse_mesh_file(const ObjectReader& object, MaterialTable& materials,
                     const ObjectContext& context, std::size_t triangles, std::vector<Object>& out);
class ObjectTexts;
// parse_objects() for the objects kept apart from `objects` (scene_stream.hpp), an empty
// array standing for them: each is checked as it would be there, then dropped.
void check_objects(const ValueReader& objects, const ObjectTexts& texts, MaterialTable& materials,
                   const ObjectContext& context);
// An object's "transform", checked at every frame when it holds tracks.
Mat4 parse_transform(const ValueReader& steps);
// The same read at the reading's one frame.
Mat4 compose_steps(const ValueReader& steps);

// --- mesh_file_object.cpp ---

// --- shape_parser.cpp ---

struct ShapeType {
  std::string_view name;
  std::span<const std::string_view> keys;  // besides "type", "material" and "transform"
  Shape (*parse)(const ObjectReader& object);
};

std::span<const ShapeType> shape_types();
// What a shape costs against Limits::max_triangles.
std::size_t triangle_count(const Shape& shape);

}  // namespace tessera
