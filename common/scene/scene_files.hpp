// The files a scene names: mesh files (OBJ, glTF, PLY, OFF) and what they bring with them.
// The parser reads a scene's `{"type": "mesh", "file": ...}` through a SceneFiles that the
// caller chooses (common/mesh_files/), so that tessera_common itself reads no file format.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "common/scene/scene.hpp"
#include "common/scene/scene_error.hpp"

namespace tessera {

enum class MeshFormat { obj, gltf, glb, ply, off };
inline constexpr std::string_view mesh_format_names[] = {"obj", "gltf", "glb", "ply", "off"};

// How a model's shading normals are chosen (docs/scene-format.md, "Mesh files").
enum class NormalsMode { file, flat, smooth };
inline constexpr std::string_view normals_mode_names[] = {"file", "flat", "smooth"};

// One mesh of a model with the material the file gives it, if any.
struct ModelPart {
  Mesh mesh;
  std::optional<Material> material;
  std::string name;  // the file's name for it (an OBJ material, a glTF mesh), for messages
};

struct Model {
  std::vector<ModelPart> parts;
  std::size_t triangles() const {
    std::size_t sum = 0;
    for (const ModelPart& part : parts) sum += part.mesh.triangles.size();
    return sum;
  }
};

// What the scene asks of one mesh file.
struct MeshFileRequest {
  std::string file;  // as the scene writes it; for an asset, its "name" or its digest
  // The farm's form: the model is the asset of this SHA-256 (64 hex digits), and the files
  // it names are the assets `files` maps their names to (docs/scene-format.md).
  std::optional<std::string> asset;
  std::map<std::string, std::string> files;
  MeshFormat format = MeshFormat::obj;
  NormalsMode normals = NormalsMode::file;
  // The triangles the scene may still have (Limits::max_triangles less those before it): a
  // file that claims more is refused before its triangles are read.
  std::size_t max_triangles = 0;
  std::size_t limit_max_triangles = 0;  // Limits::max_triangles itself, for the message
};

// What the scene asks of one texture: {"texture": FILE} or the farm's {"asset": DIGEST}.
struct TextureRequest {
  std::string file;  // as the scene writes it; for an asset, its "name" or its digest
  std::optional<std::string> asset;  // 64 hex digits
};

// A mistake in a file a scene names. `where` is "line 12" for the text formats, "byte 4096"
// for binary ones, a JSON Pointer ("/accessors/3") in a glTF, or "" for the file as a whole.
class SceneFileError : public std::runtime_error {
 public:
  SceneFileError(std::string file, std::string where, std::string detail)
      : std::runtime_error(file + (where.empty() ? "" : ":" + where) + ": " + detail),
        file_(std::move(file)),
        where_(std::move(where)) {}
  // A file over a limit of the scene's: `limit` names the Limits member ("max_triangles").
  SceneFileError(std::string file, std::string where, std::string detail, std::string limit,
                 std::uint64_t limit_value)
      : SceneFileError(std::move(file), std::move(where), std::move(detail)) {
    limit_ = std::move(limit);
    limit_value_ = limit_value;
  }
  const std::string& file() const { return file_; }
  const std::string& where() const { return where_; }
  const std::string& limit() const { return limit_; }
  std::uint64_t limit_value() const { return limit_value_; }

 private:
  std::string file_;
  std::string where_;
  std::string limit_;
  std::uint64_t limit_value_ = 0;
};

// An asset the scene names that the coordinator (or the worker's cache) does not hold.
// `pointer` is where the scene names it ("/objects/2/asset", "/objects/2/files/x.mtl").
class MissingAssetError : public SceneError {
 public:
  MissingAssetError(std::string pointer, std::string digest)
      : SceneError(std::move(pointer), "names asset sha256:" + digest +
                                           ", which the coordinator does not have; upload it "
                                           "first (tessera submit does)"),
        digest_(std::move(digest)) {}
  const std::string& digest() const { return digest_; }

 private:
  std::string digest_;
};

// Thrown by a SceneFiles for an asset it lacks: `name` is the model's, or the name the
// model's files map gives it ("" for the model itself).
struct AssetNotHeld {
  std::string name;
  std::string digest;
};

// Where a scene's files come from: a folder on disk for `tessera render`
// (common/mesh_files/folder_scene_files.hpp).
class SceneFiles {
 public:
  virtual ~SceneFiles() = default;
  // Reads a model; throws SceneFileError for a file that is missing, malformed or over a
  // limit.
  virtual Model load_model(const MeshFileRequest& request) const = 0;
  // The image a material's texture names. Throws SceneFileError for a file that is not
  // there (its pixels are read by the tracer, tracer/scene_textures.hpp).
  virtual TextureImage locate_texture(const TextureRequest& request) const = 0;
};

// A triangle of zero area up to rounding, which the parser refuses in a scene's own meshes
// and drops from a file's.
bool is_degenerate(const Vec3& a, const Vec3& b, const Vec3& c);

// The format of one of mesh_format_names, if `name` is one.
std::optional<MeshFormat> mesh_format_named(std::string_view name);
// The format a file's extension names (case-insensitive), if any.
std::optional<MeshFormat> mesh_format_of(std::string_view file);

}  // namespace tessera
