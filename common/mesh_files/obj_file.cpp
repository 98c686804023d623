// Wavefront OBJ with its MTL materials, read by tinyobjloader (Debian's
// libtinyobjloader-dev): polygons, groups and objects, negative (relative) indices. The
// model has one part per material; the MTL terms map to the seed model as
// docs/scene-format.md ("Materials from MTL") writes them.
#include <algorithm>
#include <sstream>
#include <unordered_map>

#include <tiny_obj_loader.h>

#include "common/mesh_files/mesh_builder.hpp"
#include "common/mesh_files/model_source.hpp"
#include "common/mesh_files/text_lines.hpp"

namespace tessera {
namespace {

// The number of the line of `text` whose first word is `keyword`, the `ordinal`-th such
// (0-based), or whose words after `keyword` equal `rest` when given; 0 when none is.
std::size_t find_line(std::string_view text, std::string_view keyword, std::size_t ordinal,
                      std::string_view rest = {}) {
  TextLines lines(text);
  std::string_view line;
  std::vector<std::string_view> words;
  while (lines.next(line)) {
    split_words(line, words);
    if (words.empty() || words[0] != keyword) continue;
    if (!rest.empty()) {
      const auto start = line.find(keyword) + keyword.size();
      std::string_view tail = line.substr(start);
      tail = tail.substr(0, tail.find('#'));
      while (!tail.empty() && (tail.front() == ' ' || tail.front() == '\t')) tail.remove_prefix(1);
      while (!tail.empty() && (tail.back() == ' ' || tail.back() == '\t')) tail.remove_suffix(1);
      if (tail == rest) return lines.number();
      continue;
    }
    if (ordinal-- == 0) return lines.number();
  }
  return 0;
}

// Reads each `mtllib` inside the model's folder only.
class BundleMaterials : public tinyobj::MaterialReader {
 public:
  BundleMaterials(const ModelSource& source, std::string_view obj) : source_(source), obj_(obj) {}

  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* names, std::string* warn, std::string* err) override {
    const std::string where = line_at(find_line(obj_, "mtllib", 0, name));
    const std::filesystem::path path = source_.dependency(name, where);
    ModelSource mtl{path, name, source_.bundle, source_.request, {}};
    const std::string text = mtl.read(std::uint64_t{1} << 28);
    std::istringstream stream(text);
    tinyobj::LoadMtl(names, materials, &stream, warn, err);
    return true;
  }

 private:
  const ModelSource& source_;
  std::string_view obj_;
};

Color color(const tinyobj::real_t (&c)[3]) { return Color(c[0], c[1], c[2]); }
Color non_negative(const Color& c) { return glm::max(c, Color(0.0)); }

// A map statement's texture, named relative to the model's folder as the MTL is.
std::optional<TexturedColor> map_texture(const ModelSource& source, const std::string& name,
                                         const tinyobj::texture_option_t& options,
                                         const Color& scale) {
  if (name.empty()) return std::nullopt;
  TexturedColor texture;
  const std::filesystem::path path = source.dependency(name, "");
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    source.fail("", "its MTL names the texture \"" + name + "\", which is not there");
  texture.image = {name, path.string(), nullptr, {}};
  texture.scale = scale;
  texture.wrap = options.clamp ? TextureWrap::clamp : TextureWrap::repeat;
  return texture;
}

Material from_mtl(const tinyobj::material_t& mtl, const ModelSource& source) {
  Material m;
  m.ambient = non_negative(color(mtl.ambient));
  m.diffuse = non_negative(color(mtl.diffuse));
  m.specular = non_negative(color(mtl.specular));
  m.emission = non_negative(color(mtl.emission));
  m.shininess = std::max<double>(mtl.shininess, 0.0);
  m.ior = mtl.ior > 0 ? mtl.ior : 1.0;
  // tinyobjloader reads an absent illum as 0, which is then taken to mean 2 (highlights).
  const int illum = mtl.illum == 0 ? 2 : mtl.illum;
  if (illum == 1) m.specular = Color(0.0);
  m.reflection = illum >= 3 ? m.specular : Color(0.0);
  const Color filter = color(mtl.transmittance);
  const Color tf = filter == Color(0.0) ? Color(1.0) : non_negative(filter);
  const double opacity = std::clamp<double>(mtl.dissolve, 0.0, 1.0);
  if (opacity < 1.0) {
    m.transmission = (1.0 - opacity) * tf;
    m.diffuse *= opacity;
    m.ambient *= opacity;
  } else if ((illum == 6 || illum == 7) && filter != Color(0.0)) {
    m.transmission = tf;
  }
  // Each map is multiplied by its colour, as the MTL format has it; map_Kd colours K_A too
  // where there is no map_Ka (docs/scene-format.md, "Materials from MTL").
  m.texture(TexturedTerm::diffuse) =
      map_texture(source, mtl.diffuse_texname, mtl.diffuse_texopt, m.diffuse);
  m.texture(TexturedTerm::ambient) =
      mtl.ambient_texname.empty()
          ? map_texture(source, mtl.diffuse_texname, mtl.diffuse_texopt, m.ambient)
          : map_texture(source, mtl.ambient_texname, mtl.ambient_texopt, m.ambient);
  if (illum != 1)
    m.texture(TexturedTerm::specular) =
        map_texture(source, mtl.specular_texname, mtl.specular_texopt, m.specular);
  m.texture(TexturedTerm::emission) =
      map_texture(source, mtl.emissive_texname, mtl.emissive_texopt, m.emission);
  return m;
}

// A face corner's indices: its position, normal and uv (-1: none).
struct Corner {
  int v, vn, vt;
  bool operator==(const Corner&) const = default;
};
struct CornerHash {
  std::size_t operator()(const Corner& c) const {
    std::uint64_t h = static_cast<std::uint32_t>(c.v);
    h = h * 0x9e3779b97f4a7c15ull + static_cast<std::uint32_t>(c.vn);
    h = h * 0x9e3779b97f4a7c15ull + static_cast<std::uint32_t>(c.vt);
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

struct PartBuilder {
  RawMesh raw;
  std::unordered_map<Corner, std::uint32_t, CornerHash> corners;  // -> position index
  bool all_normals = true;
  bool all_uvs = true;
};

}  // namespace

Model read_obj(const ModelSource& source) {
  const std::string text = source.read();
  std::istringstream stream(text);
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  BundleMaterials reader(source, text);
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, &reader, false,
                        false)) {
    // tinyobjloader words its errors "... line 12.)": the line goes where every format's does.
    std::string where;
    if (const auto at = err.rfind("line "); at != std::string::npos) {
      const auto digits = err.find_first_not_of("0123456789", at + 5);
      if (digits > at + 5) where = err.substr(at, digits - at);
    }
    source.fail(where, err.empty() ? "could not be read as OBJ" : err.substr(0, err.find('\n')));
  }
  const std::size_t positions = attrib.vertices.size() / 3;
  const std::size_t normals = attrib.normals.size() / 3;
  const std::size_t uvs = attrib.texcoords.size() / 2;
  const bool use_file_normals = source.request->normals == NormalsMode::file;
  std::vector<PartBuilder> parts(materials.size() + 1);  // the last: faces with no material
  std::size_t face_number = 0;
  std::size_t triangles = 0;
  std::vector<std::uint32_t> corners;
  for (const tinyobj::shape_t& shape : shapes) {
    std::size_t next = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f, ++face_number) {
      const std::size_t n = shape.mesh.num_face_vertices[f];
      const int material = shape.mesh.material_ids[f];
      PartBuilder& part =
          parts[material >= 0 && static_cast<std::size_t>(material) < materials.size()
                    ? material
                    : materials.size()];
      corners.clear();
      for (std::size_t k = 0; k < n; ++k) {
        const tinyobj::index_t& index = shape.mesh.indices[next + k];
        const bool has_normal = use_file_normals && index.normal_index >= 0;
        const bool has_uv = index.texcoord_index >= 0;
        if (index.vertex_index < 0 || static_cast<std::size_t>(index.vertex_index) >= positions ||
            (has_normal && static_cast<std::size_t>(index.normal_index) >= normals) ||
            (has_uv && static_cast<std::size_t>(index.texcoord_index) >= uvs)) {
          source.fail(line_at(find_line(text, "f", face_number)),
                      "a face names a vertex, uv or normal that does not exist (" +
                          std::to_string(positions) + " vertices, " + std::to_string(uvs) +
                          " uvs and " + std::to_string(normals) + " normals are defined)");
        }
        const Corner key{index.vertex_index, has_normal ? index.normal_index : -1,
                         has_uv ? index.texcoord_index : -1};
        const auto [at, added] =
            part.corners.try_emplace(key, static_cast<std::uint32_t>(part.raw.positions.size()));
        if (added) {
          const float* v = &attrib.vertices[3 * index.vertex_index];
          part.raw.positions.emplace_back(v[0], v[1], v[2]);
          if (has_uv) {
            const float* vt = &attrib.texcoords[2 * index.texcoord_index];
            part.raw.uvs.emplace_back(vt[0], vt[1]);
          } else {
            part.all_uvs = false;
            part.raw.uvs.emplace_back(0.0f);
          }
          if (has_normal) {
            const float* vn = &attrib.normals[3 * index.normal_index];
            part.raw.normals.emplace_back(vn[0], vn[1], vn[2]);
          } else {
            part.all_normals = false;
            part.raw.normals.emplace_back(0.0);
          }
        }
        corners.push_back(at->second);
      }
      next += n;
      if (n < 3) continue;
      triangles += n - 2;
      if (triangles > source.request->max_triangles)
        source.fail_triangles(line_at(find_line(text, "f", face_number)), triangles);
      add_polygon(corners, part.raw.triangles);
    }
  }
  Model model;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    PartBuilder& part = parts[i];
    if (!part.all_normals) part.raw.normals.clear();  // a face without normals: shaded flat
    if (!part.all_uvs) part.raw.uvs.clear();          // a face without uvs: as if none had them
    auto mesh = finish_mesh(std::move(part.raw), source.request->normals);
    if (!mesh) continue;
    if (i < materials.size())
      model.parts.push_back({std::move(*mesh), from_mtl(materials[i], source), materials[i].name});
    else
      model.parts.push_back({std::move(*mesh), std::nullopt, "(no material)"});
  }
  return model;
}

}  // namespace tessera
