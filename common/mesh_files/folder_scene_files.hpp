// Mesh files on this machine's disk, named relative to a folder (the scene file's): what
// `tessera render` reads a scene's meshes through.
#pragma once

#include <filesystem>

#include "common/scene_files.hpp"

namespace tessera {

class FolderSceneFiles : public SceneFiles {
 public:
  explicit FolderSceneFiles(std::filesystem::path folder) : folder_(std::move(folder)) {}
  Model load_model(const MeshFileRequest& request) const override;

 private:
  std::filesystem::path folder_;
};

// Reads the model file at `path`, whose own files resolve in its folder; `request.file` is
// the name errors give it.
Model read_model_file(const std::filesystem::path& path, const MeshFileRequest& request);

}  // namespace tessera
