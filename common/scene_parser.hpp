// JSON scene format version 1 → validated Scene. Every rule of docs/scene-format.md is
// checked here, once; a violation throws SceneError naming the JSON Pointer.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "common/json_fast_parse.hpp"

#include "common/scene.hpp"
#include "common/scene_error.hpp"
#include "common/scene_files.hpp"

namespace tessera {

Scene parse_scene(const nlohmann::json& document, const Limits& limits = {});
// The same for a document whose big mesh arrays were lifted out (parse_json_fast_lifted());
// throws LiftedArrayRefused where one of them breaks a rule. Mesh files are read through
// `files`; with none, a mesh object that names a file is a SceneError.
Scene parse_scene(const nlohmann::json& document, const Limits& limits, const LiftedArrays* lifted,
                  const SceneFiles* files = nullptr);

// Parses JSON text; a syntax error or nesting deeper than 64 levels is a SceneError at ""
// naming line and column.
nlohmann::json parse_json_text(std::string_view text);

// Parses JSON text first; a syntax error is a SceneError at "" naming line and column.
// `edit`, if given, changes the document before it is read as a scene (not the meshes'
// arrays, which may have been lifted out of it). The Scene and the
// errors are those of parse_scene(parse_json_text(text), limits), but a mesh's big arrays
// go from simdjson straight into the Scene, without a node per number.
Scene parse_scene_text(std::string_view text, const Limits& limits = {},
                       const std::function<void(nlohmann::json&)>& edit = {},
                       const SceneFiles* files = nullptr);

// A whole file's text; an unreadable file is a std::runtime_error.
std::string read_text_file(const std::filesystem::path& path);
// Reads a file as parse_json_text does; an unreadable file is a std::runtime_error.
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace tessera
