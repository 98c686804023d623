// A scene object that names a mesh file: {"type": "mesh", "file": "models/bunny.obj"}.
#include <algorithm>
#include <cctype>

#include "common/protocol/asset_digest.hpp"
#include "common/scene/scene_parser_parts.hpp"
#include "common/text/ascii_case.hpp"

namespace tessera {
namespace {

constexpr std::string_view mesh_file_keys[] = {"type",   "material", "transform", "file",
                                               "format", "normals",  "thin"};
constexpr std::string_view mesh_asset_keys[] = {"type", "material", "transform", "asset", "files",
                                                "name", "format",   "normals",   "thin"};

}  // namespace

std::string read_digest(const ValueReader& value) {
  using protocol::AssetDigest;
  if (!value.json().is_string())
    value.fail_type("an asset digest (" + std::string(AssetDigest::kForm) + ")");
  const std::string& text = value.string();
  const auto digest = AssetDigest::parse(text);
  if (!digest) value.fail("must be " + std::string(AssetDigest::kForm) + ", got " + quote(text));
  return digest->hex();
}

namespace {

// The farm's form: {"asset": DIGEST, "format": "obj", "files": {"x.mtl": DIGEST}}.
void read_asset(const ObjectReader& object, MeshFileRequest& request) {
  request.asset = read_digest(object.require("asset"));
  if (const auto files = object.find("files")) {
    const ObjectReader names(*files, "an object mapping the model's file names to digests");
    for (const auto& [name, unused] : names.members())
      request.files.emplace(name, read_digest(files->member(name)));
  }
  const auto name = object.find("name");
  if (name && !name->json().is_string()) name->fail_type("a file name (string)");
  request.file = name ? name->string() : protocol::AssetDigest::of_hex(*request.asset).short_text();
}

MeshFormat read_format(const ObjectReader& reader, const ValueReader& file) {
  if (const auto format = reader.find("format")) {
    return *mesh_format_named(format->choice(mesh_format_names));
  }
  const auto format = mesh_format_of(file.string());
  if (!format) {
    file.fail(
        "has no extension that names a mesh format (.obj, .gltf, .glb, .ply, .off); "
        "say which with \"format\"");
  }
  return *format;
}

NormalsMode read_normals(const ObjectReader& reader) {
  const auto normals = reader.find("normals");
  return normals ? enum_choice<NormalsMode>(*normals, normals_mode_names) : NormalsMode::file;
}

}  // namespace

std::optional<MeshFormat> mesh_format_named(std::string_view name) {
  for (std::size_t i = 0; i < std::size(mesh_format_names); ++i)
    if (name == mesh_format_names[i]) return static_cast<MeshFormat>(i);
  return std::nullopt;
}

std::optional<MeshFormat> mesh_format_of(std::string_view file) {
  const auto dot = file.rfind('.');
  if (dot == std::string_view::npos || file.find('/', dot) != std::string_view::npos)
    return std::nullopt;
  return mesh_format_named(ascii_lower(file.substr(dot + 1)));
}

bool is_mesh_file(const ObjectReader& object) {
  const auto type = object.find("type");
  return type && type->json().is_string() && type->json().get_ref<const std::string&>() == "mesh" &&
         (object.members().contains("file") || object.members().contains("asset"));
}

void parse_mesh_file(const ObjectReader& object, MaterialTable& materials,
                     const ObjectContext& context, std::size_t triangles,
                     std::vector<Object>& out) {
  const std::size_t limit = context.limits.max_triangles;
  MeshFileRequest request;
  const bool asset = object.members().contains("asset");
  const ValueReader file = object.require(asset ? "asset" : "file");
  if (asset) {
    object.allow_only(mesh_asset_keys);
    read_asset(object, request);
    request.format = read_format(object, object.require("format"));
  } else {
    object.allow_only(mesh_file_keys);
    if (!file.json().is_string()) file.fail_type("a file name (string)");
    if (file.string().empty()) file.fail("must name a file, got \"\"");
    request.file = file.string();
    request.format = read_format(object, file);
  }
  request.normals = read_normals(object);
  request.max_triangles = limit - std::min(triangles, limit);
  request.limit_max_triangles = limit;
  const bool thin = object.boolean_or("thin", false);
  Mat4 transform{1.0};
  if (const auto steps = object.find("transform")) transform = parse_transform(*steps);
  std::optional<std::uint32_t> material;
  if (const auto reference = object.find("material")) material = materials.resolve(*reference);
  if (context.files == nullptr) {
    file.fail(
        "names a mesh file, which this reader of the scene cannot open (tessera render reads "
        "files beside the scene; tessera submit uploads them as assets)");
  }

  Model model;
  try {
    model = context.files->load_model(request);
  } catch (const AssetNotHeld& missing) {
    throw MissingAssetError(missing.name.empty()
                                ? file.pointer()
                                : object.pointer() + "/files/" + pointer_token(missing.name),
                            missing.digest);
  } catch (const SceneFileError& error) {
    if (!error.limit().empty()) file.fail_limit(error.what(), error.limit(), error.limit_value());
    file.fail(error.what());
  }
  for (ModelPart& part : model.parts) {
    Object made;
    part.mesh.thin = thin;
    made.shape = std::move(part.mesh);
    made.transform = transform;
    if (material)
      made.material = *material;
    else if (part.material)
      made.material = materials.add(*part.material, file);
    out.push_back(std::move(made));
  }
}

}  // namespace tessera
