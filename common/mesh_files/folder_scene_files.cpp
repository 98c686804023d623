#include "common/mesh_files/folder_scene_files.hpp"

#include "common/mesh_files/model_source.hpp"

namespace tessera {

Model read_model_file(const std::filesystem::path& path, const MeshFileRequest& request) {
  const ModelSource source{path, request.file, path.parent_path(), &request};
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

Model FolderSceneFiles::load_model(const MeshFileRequest& request) const {
  return read_model_file(folder_ / request.file, request);
}

}  // namespace tessera
