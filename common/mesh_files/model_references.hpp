// The files a model file names (an OBJ's MTL libraries and the texture maps in them, a
// glTF's buffers and images), as it names them: what travels to the farm with it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "common/scene/scene_files.hpp"

namespace tessera {

// Names relative to the model's folder, each once, in the order met; data: URIs are not
// files. Throws SceneFileError for a model (or MTL) that cannot be read or parsed, or a
// name that leaves the model's folder.
std::vector<std::string> model_references(const std::filesystem::path& model, MeshFormat format,
                                          const std::string& name);

}  // namespace tessera
