#include "common/mesh_files/model_references.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

#include <nlohmann/json.hpp>

#include "common/mesh_files/model_source.hpp"
#include "common/mesh_files/text_lines.hpp"

namespace tessera {
namespace {

void add_once(std::vector<std::string>& names, std::string name) {
  if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(std::move(name));
}

// Each word after `mtllib`; and in each MTL, the file of every map statement (its last
// word: options such as -s or -clamp come first).
void obj_references(const ModelSource& source, std::vector<std::string>& names) {
  const std::string text = source.read();
  TextLines lines(text);
  std::string_view line;
  std::vector<std::string_view> words;
  std::vector<std::string> libraries;
  while (lines.next(line)) {
    split_words(line, words);
    if (words.size() < 2 || words[0] != "mtllib") continue;
    for (std::size_t i = 1; i < words.size(); ++i) {
      const std::string where = line_at(lines.number());
      source.dependency(words[i], where);  // refuses a name outside the folder
      add_once(names, std::filesystem::path(words[i]).lexically_normal().generic_string());
      libraries.push_back(std::string(words[i]));
    }
  }
  for (const std::string& library : libraries) {
    const ModelSource mtl{
        source.dependency(library, ""), library, source.bundle, source.request, {}};
    std::error_code missing;
    if (!std::filesystem::exists(mtl.path, missing)) continue;  // tinyobjloader goes on without
    const std::string mtl_text = mtl.read(std::uint64_t{1} << 28);
    TextLines mtl_lines(mtl_text);
    while (mtl_lines.next(line)) {
      split_words(line, words);
      if (words.size() < 2) continue;
      const std::string_view keyword = words[0];
      if (!keyword.starts_with("map_") && keyword != "bump" && keyword != "disp" &&
          keyword != "decal" && keyword != "refl" && keyword != "norm")
        continue;
      // A texture is named relative to the model's folder, as the MTL is.
      source.dependency(words.back(), line_at(mtl_lines.number()));
      add_once(names, std::filesystem::path(words.back()).lexically_normal().generic_string());
    }
  }
}

// A buffer's or an image's URI as the file name tinygltf reads for it (the model's own
// reader, gltf_file.cpp): "%XX" is the byte XX (a digit that is not hex counts as 0) and
// '+' is a space. Both sides must name a file alike, or the farm's "files" map would hold
// a name its reader never asks for.
std::string gltf_file_name(std::string_view uri) {
  const auto nibble = [](char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return 0;
  };
  std::string out;
  out.reserve(uri.size());
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '+') {
      out += ' ';
    } else if (uri[i] == '%' && i + 2 < uri.size()) {
      out += static_cast<char>(nibble(uri[i + 1]) * 16 + nibble(uri[i + 2]));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// A .glb's JSON chunk, or a .gltf's whole text.
std::string gltf_json(const ModelSource& source, const std::string& bytes) {
  if (source.request->format != MeshFormat::glb) return bytes;
  std::uint32_t length = 0;
  if (bytes.size() < 20 || bytes.compare(0, 4, "glTF") != 0) source.fail("", "is not a .glb file");
  std::memcpy(&length, bytes.data() + 12, 4);
  if (length > bytes.size() - 20) source.fail("byte 12", "its JSON chunk runs past the file's end");
  return bytes.substr(20, length);
}

void gltf_references(const ModelSource& source, std::vector<std::string>& names) {
  const std::string bytes = source.read(std::uint64_t{1} << 32);
  const nlohmann::json gltf = nlohmann::json::parse(gltf_json(source, bytes), nullptr, false);
  if (gltf.is_discarded() || !gltf.is_object()) source.fail("", "is not valid glTF JSON");
  for (const char* array : {"buffers", "images"}) {
    const auto found = gltf.find(array);
    if (found == gltf.end() || !found->is_array()) continue;
    for (std::size_t i = 0; i < found->size(); ++i) {
      const nlohmann::json& item = (*found)[i];
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string& raw = item["uri"].get_ref<const std::string&>();
      if (raw.starts_with("data:")) continue;
      const std::string uri = gltf_file_name(raw);
      const std::string where = "/" + std::string(array) + "/" + std::to_string(i) + "/uri";
      source.dependency(uri, where);
      add_once(names, std::filesystem::path(uri).lexically_normal().generic_string());
    }
  }
}

}  // namespace

std::vector<std::string> model_references(const std::filesystem::path& model, MeshFormat format,
                                          const std::string& name) {
  MeshFileRequest request;
  request.file = name;
  request.format = format;
  const ModelSource source{model, name, model.parent_path(), &request, {}};
  std::vector<std::string> names;
  if (format == MeshFormat::obj) obj_references(source, names);
  if (format == MeshFormat::gltf || format == MeshFormat::glb) gltf_references(source, names);
  return names;
}

}  // namespace tessera
