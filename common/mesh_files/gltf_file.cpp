// glTF 2.0, .gltf (with its .bin and images beside it, or embedded as data: URIs) and .glb,
// read by tinygltf (Debian's libtinygltf-dev). Every triangle primitive of the scene's node
// hierarchy becomes a part, its node's transform applied to its positions and normals;
// strips and fans become triangles. Materials map to the seed model as
// docs/scene-format.md ("Materials from glTF") writes them.
#include <tiny_gltf.h>

#include "common/mesh_files/gltf_reading.hpp"
#include "common/mesh_files/mesh_builder.hpp"
#include "common/mesh_files/model_source.hpp"

namespace tessera {
namespace {

// tinygltf reads the model's other files through these, each inside the model's folder.
struct BundleFiles {
  const ModelSource* source;
  std::optional<SceneFileError> refused;  // the first reference that left the folder
};

std::optional<std::filesystem::path> in_bundle(const std::string& name, void* user) {
  auto* files = static_cast<BundleFiles*>(user);
  try {
    return files->source->dependency(name, "");
  } catch (const SceneFileError& error) {
    if (!files->refused) files->refused = error;
    return std::nullopt;
  }
}

bool file_exists(const std::string& name, void* user) {
  const auto path = in_bundle(name, user);
  std::error_code error;
  return path && std::filesystem::is_regular_file(*path, error);
}

std::string expand(const std::string& name, void*) { return name; }

bool read_whole(std::vector<unsigned char>* out, std::string* err, const std::string& name,
                void* user) {
  const auto path = in_bundle(name, user);
  if (!path) return false;
  auto* files = static_cast<BundleFiles*>(user);
  try {
    const ModelSource file{*path, name, files->source->bundle, files->source->request, {}};
    const std::string bytes = file.read(std::uint64_t{1} << 32);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const SceneFileError& error) {
    *err += error.what();
    return false;
  }
}

bool write_nothing(std::string*, const std::string&, const std::vector<unsigned char>&, void*) {
  return false;
}

// Images are kept as their file's bytes, undecoded: the tracer decodes the textures
// (tracer/scene_textures.hpp), and a model read only to be checked decodes none.
bool keep_image_bytes(tinygltf::Image*, const int index, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void* user) {
  auto& kept = *static_cast<std::vector<std::shared_ptr<const std::string>>*>(user);
  if (index < 0 || size < 0) return true;
  if (kept.size() <= static_cast<std::size_t>(index)) kept.resize(index + 1);
  kept[index] = std::make_shared<const std::string>(reinterpret_cast<const char*>(bytes),
                                                    static_cast<std::size_t>(size));
  return true;
}

tinygltf::Model load(const ModelSource& source, MeshFormat format,
                     std::vector<std::shared_ptr<const std::string>>& images) {
  const std::string bytes = source.read(std::uint64_t{1} << 32);
  BundleFiles files{&source, std::nullopt};
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, &images);
  loader.SetFsCallbacks({file_exists, expand, read_whole, write_nothing, &files});
  tinygltf::Model model;
  std::string err, warn;
  const bool ok =
      format == MeshFormat::glb
          ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                        reinterpret_cast<const unsigned char*>(bytes.data()),
                                        static_cast<unsigned int>(bytes.size()), "")
          : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(),
                                       static_cast<unsigned int>(bytes.size()), "");
  if (files.refused) throw *files.refused;
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    source.fail("", err.empty() ? "could not be read as glTF" : err);
  }
  return model;
}

}  // namespace

Model read_gltf(const ModelSource& source) {
  std::vector<std::shared_ptr<const std::string>> images;
  const tinygltf::Model gltf = load(source, source.request->format, images);
  return gltf_model(gltf, source, images);
}

}  // namespace tessera
