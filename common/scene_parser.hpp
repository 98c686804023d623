// JSON scene format version 1 → validated Scene. Every rule of docs/scene-format.md is
// checked here, once; a violation throws SceneError naming the JSON Pointer.
#pragma once

#include <filesystem>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "common/scene.hpp"
#include "common/scene_error.hpp"

namespace tessera {

Scene parse_scene(const nlohmann::json& document, const Limits& limits = {});

// Parses JSON text; a syntax error or nesting deeper than 64 levels is a SceneError at ""
// naming line and column.
nlohmann::json parse_json_text(std::string_view text);

// Parses JSON text first; a syntax error is a SceneError at "" naming line and column.
Scene parse_scene_text(std::string_view text, const Limits& limits = {});

// Reads a file as parse_scene_text does; an unreadable file is a std::runtime_error.
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace tessera
