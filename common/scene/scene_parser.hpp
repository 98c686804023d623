// JSON scene format version 1 → validated Scene. Every rule of docs/scene-format.md is
// checked here, once; a violation throws SceneError naming the JSON Pointer.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "common/scene/json_fast_parse.hpp"

#include "common/scene/scene.hpp"
#include "common/scene/scene_error.hpp"
#include "common/scene/scene_files.hpp"

namespace tessera {

Scene parse_scene(const nlohmann::json& document, const Limits& limits = {});
// The same for a document whose big mesh arrays were lifted out (parse_json_fast_lifted());
// throws LiftedArrayRefused where one of them breaks a rule. Mesh files are read through
// `files`; with none, a mesh object that names a file is a SceneError.
Scene parse_scene(const nlohmann::json& document, const Limits& limits, const LiftedArrays* lifted,
                  const SceneFiles* files = nullptr);

// An animated scene read at `frame` of its range, with the same rules (parse_scene() reads
// the first frame, and checks every other frame of each track too); a frame outside the
// range is a SceneError at "/animation/frames".
Scene parse_scene_frame(const nlohmann::json& document, int frame, const Limits& limits,
                        const LiftedArrays* lifted = nullptr, const SceneFiles* files = nullptr);
// `scene`, read from `document` at another frame, moved to `frame` by reading again only
// what its tracks change: the camera, the lights, the background, the ambient light and the
// named materials. Not for a scene with tracks in its objects
// (Animation::changes_objects()), which parse_scene_frame() reads whole.
Scene advance_scene(const nlohmann::json& document, Scene scene, int frame, const Limits& limits,
                    const SceneFiles* files = nullptr);

// Parses JSON text; a syntax error or nesting deeper than 64 levels is a SceneError at ""
// naming line and column.
nlohmann::json parse_json_text(std::string_view text);

// Parses JSON text first; a syntax error is a SceneError at "" naming line and column.
// `edit`, if given, changes the document before it is read as a scene (not the meshes'
// arrays, which may have been lifted out of it). The Scene and the
// errors are those of parse_scene(parse_json_text(text), limits), but a mesh's big arrays
// go from simdjson straight into the Scene, without a node per number.
// `frame`: as parse_scene_frame(); none reads the first, as parse_scene().
Scene parse_scene_text(std::string_view text, const Limits& limits = {},
                       const std::function<void(nlohmann::json&)>& edit = {},
                       const SceneFiles* files = nullptr, std::optional<int> frame = std::nullopt);

// A whole file's text; an unreadable file is a std::runtime_error.
std::string read_text_file(const std::filesystem::path& path);
// Reads a file as parse_json_text does; an unreadable file is a std::runtime_error.
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace tessera
