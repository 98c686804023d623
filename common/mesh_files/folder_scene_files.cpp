#include "common/mesh_files/folder_scene_files.hpp"

#include <map>

#include "common/mesh_files/model_source.hpp"

namespace tessera {

namespace {

Model read_model(const ModelSource& source) {
  const MeshFileRequest& request = *source.request;
  Model model;
  switch (request.format) {
    case MeshFormat::obj:
      model = read_obj(source);
      break;
    case MeshFormat::gltf:
    case MeshFormat::glb:
      model = read_gltf(source);
      break;
    case MeshFormat::ply:
      model = read_ply(source);
      break;
    case MeshFormat::off:
      model = read_off(source);
      break;
  }
  if (model.parts.empty())
    source.fail("", "has no triangles (degenerate ones, points and lines are not drawn)");
  return model;
}

}  // namespace

Model read_model_file(const std::filesystem::path& path, const MeshFileRequest& request) {
  return read_model({path, request.file, path.parent_path(), &request, {}});
}

FolderSceneFiles::FolderSceneFiles(std::filesystem::path folder,
                                   std::vector<std::filesystem::path> allowed)
    : folder_(std::move(folder)), confined_(true) {
  allowed.insert(allowed.begin(), folder_.empty() ? std::filesystem::path(".") : folder_);
  for (const std::filesystem::path& root : allowed) {
    std::error_code error;
    const std::filesystem::path real = std::filesystem::weakly_canonical(root, error);
    if (!error) roots_.push_back(real);
  }
}

std::filesystem::path FolderSceneFiles::inside(const std::string& name) const {
  const std::filesystem::path path = folder_ / name;
  if (!confined_) return path;
  // After every link: a link beside the scene that leads out of its folder leads out.
  std::error_code error;
  const std::filesystem::path real = std::filesystem::weakly_canonical(path, error);
  if (!error)
    for (const std::filesystem::path& root : roots_) {
      const std::filesystem::path relative = real.lexically_relative(root);
      if (!relative.empty() && *relative.begin() != "..") return path;
    }
  throw SceneFileError(name, "",
                       "is outside the scene's folder; a scene sent to the farm names only files "
                       "beside it or below it (--allow-path DIR allows the files under DIR too)");
}

Model FolderSceneFiles::load_model(const MeshFileRequest& request) const {
  if (request.asset) {
    throw SceneFileError(request.file, "",
                         "is an asset (sha256:...), which only the farm holds; name the file "
                         "itself with \"file\" to render here");
  }
  return read_model_file(inside(request.file), request);
}

TextureImage FolderSceneFiles::locate_texture(const TextureRequest& request) const {
  if (request.asset) {
    throw SceneFileError(request.file, "",
                         "is an asset (sha256:...), which only the farm holds; name the file "
                         "itself with \"texture\" to render here");
  }
  const std::filesystem::path path = inside(request.file);
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw SceneFileError(request.file, "", "is not there (looked for " + path.string() + ")");
  return {request.file, path.string(), nullptr, {}};
}

TextureImage AssetSceneFiles::locate_texture(const TextureRequest& request) const {
  if (!request.asset) {
    throw SceneFileError(request.file, "",
                         "is a file on the machine that sent the scene; the farm reads textures "
                         "as assets (tessera submit uploads them)");
  }
  const auto path = locate_(*request.asset);
  if (!path) throw AssetNotHeld{"", *request.asset};
  return {request.file, path->string(), nullptr, {}};
}

Model AssetSceneFiles::load_model(const MeshFileRequest& request) const {
  if (!request.asset) {
    throw SceneFileError(request.file, "",
                         "is a file on the machine that sent the scene; the farm reads meshes "
                         "as assets (tessera submit uploads them)");
  }
  const auto model = locate_(*request.asset);
  if (!model) throw AssetNotHeld{"", *request.asset};
  // Every asset the scene names must be there, whether or not the model reads it; each is
  // located once (on a worker, fetched or checked against its digest) and read from there.
  std::map<std::string, std::filesystem::path> held;
  for (const auto& [name, digest] : request.files) {
    auto path = locate_(digest);
    if (!path) throw AssetNotHeld{name, digest};
    held.emplace(name, std::move(*path));
  }
  ModelSource source{*model, request.file, {}, &request, {}};
  source.lookup = [&held, &request](const std::string& name, const std::string& where) {
    const auto path = held.find(name);
    if (path == held.end()) {
      throw SceneFileError(
          request.file, where,
          "names \"" + name + "\", which the scene's \"files\" do not map to an asset");
    }
    return path->second;
  };
  return read_model(source);
}

}  // namespace tessera
