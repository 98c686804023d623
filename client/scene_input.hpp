// A scene file as the CLI takes it: our JSON, or a COS 426 .scn converted on the way in.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace tessera {

// The JSON text of the scene at `path`. A .scn (any case) is converted by import_scn with
// the image size given, if any, since its camera's angle is horizontal; its mesh files are
// then named relative to its folder. Throws ScnError for a broken .scn and
// std::runtime_error for a file that cannot be read.
std::string read_scene_text(const std::filesystem::path& path, std::optional<int> width = {},
                            std::optional<int> height = {});

}  // namespace tessera
