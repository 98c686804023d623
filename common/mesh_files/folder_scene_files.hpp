// Mesh files on this machine's disk, named relative to a folder (the scene file's): what
// `tessera render` reads a scene's meshes through.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <vector>

#include "common/scene/scene_files.hpp"

namespace tessera {

class FolderSceneFiles : public SceneFiles {
 public:
  // Reads whatever the scene names: for a scene rendered here, where the files go nowhere.
  explicit FolderSceneFiles(std::filesystem::path folder) : folder_(std::move(folder)) {}
  // Reads only files inside `folder` or one of `allowed`, after links: for a scene whose
  // files are sent on (tessera submit), so that a scene someone else wrote cannot send
  // ~/.ssh/id_ed25519 to a farm as its "texture". A name outside them is refused before
  // any of its bytes is read.
  FolderSceneFiles(std::filesystem::path folder, std::vector<std::filesystem::path> allowed);
  Model load_model(const MeshFileRequest& request) const override;
  TextureImage locate_texture(const TextureRequest& request) const override;

 private:
  // folder_ / name, once it is known to be inside the allowed folders (when confined).
  std::filesystem::path inside(const std::string& name) const;

  std::filesystem::path folder_;
  bool confined_ = false;
  std::vector<std::filesystem::path> roots_;  // when confined: folder_, then `allowed`, real
};

// Mesh files as the farm has them: assets, files named by their SHA-256, which `locate`
// finds (the coordinator's asset store, a worker's cache). A model's own files are the
// assets its "files" map names to.
class AssetSceneFiles : public SceneFiles {
 public:
  using Locate = std::function<std::optional<std::filesystem::path>(const std::string& sha256)>;
  explicit AssetSceneFiles(Locate locate) : locate_(std::move(locate)) {}
  // Throws AssetNotHeld for an asset `locate` does not find.
  Model load_model(const MeshFileRequest& request) const override;
  TextureImage locate_texture(const TextureRequest& request) const override;

 private:
  Locate locate_;
};

// Reads the model file at `path`, whose own files resolve in its folder; `request.file` is
// the name errors give it.
Model read_model_file(const std::filesystem::path& path, const MeshFileRequest& request);

}  // namespace tessera
