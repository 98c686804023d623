#include "common/mesh_files/gltf_reading.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <map>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/mesh_files/mesh_builder.hpp"

namespace tessera {
namespace {

constexpr int float_type = TINYGLTF_COMPONENT_TYPE_FLOAT;

// An accessor's elements where they lie in their buffer, every byte of them checked to be
// inside it.
struct AccessorView {
  const unsigned char* data = nullptr;
  std::size_t stride = 0;
  std::size_t count = 0;
  int component_type = 0;
};

std::string at(std::string_view array, std::size_t index) {
  return "/" + std::string(array) + "/" + std::to_string(index);
}

std::size_t component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

class GltfReader {
 public:
  GltfReader(const tinygltf::Model& gltf, const ModelSource& source,
             const std::vector<std::shared_ptr<const std::string>>& images)
      : gltf_(gltf), source_(source), images_(images) {}

  AccessorView view(int index, int type, std::size_t components, bool indices,
                    const std::string& from) const {
    if (index < 0 || static_cast<std::size_t>(index) >= gltf_.accessors.size())
      source_.fail(from, "names accessor " + std::to_string(index) + ", which does not exist");
    const std::string pointer = at("accessors", index);
    const tinygltf::Accessor& accessor = gltf_.accessors[index];
    if (accessor.sparse.isSparse)
      source_.fail(pointer + "/sparse", "sparse accessors are not read");
    if (accessor.type != type)
      source_.fail(pointer + "/type", "must be " + std::string(components == 1   ? "SCALAR"
                                                               : components == 2 ? "VEC2"
                                                                                 : "VEC3"));
    const int ct = accessor.componentType;
    if (indices ? (ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                   ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                   ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
                : (ct != float_type || accessor.normalized))
      source_.fail(pointer + "/componentType",
                   indices ? "indices must be unsigned 8-, 16- or 32-bit integers"
                           : "must be FLOAT (5126); quantized attributes are not read");
    if (accessor.bufferView < 0 ||
        static_cast<std::size_t>(accessor.bufferView) >= gltf_.bufferViews.size())
      source_.fail(pointer + "/bufferView", "must name a bufferView");
    const tinygltf::BufferView& bv = gltf_.bufferViews[accessor.bufferView];
    const std::string bv_pointer = at("bufferViews", accessor.bufferView);
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= gltf_.buffers.size())
      source_.fail(bv_pointer + "/buffer", "must name a buffer");
    const auto& data = gltf_.buffers[bv.buffer].data;
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
      source_.fail(bv_pointer, "lies beyond the end of its buffer");
    const std::size_t element = component_size(ct) * components;
    const std::size_t stride = bv.byteStride == 0 ? element : bv.byteStride;
    if (stride < element) source_.fail(bv_pointer + "/byteStride", "is smaller than an element");
    AccessorView result{data.data() + bv.byteOffset + accessor.byteOffset, stride, accessor.count,
                        ct};
    const std::size_t length = bv.byteLength;
    if (accessor.count > 0 &&
        (accessor.byteOffset > length || element > length - accessor.byteOffset ||
         accessor.count - 1 > (length - accessor.byteOffset - element) / stride))
      source_.fail(pointer, "reads beyond the end of its bufferView");
    return result;
  }

  // An accessor of N floats an element, each element made into a T by `make`; a value that
  // is not finite is an error at the accessor.
  template <std::size_t N, typename T, typename Make>
  std::vector<T> floats(int index, int type, const std::string& from, Make make) const {
    const AccessorView v = view(index, type, N, false, from);
    std::vector<T> out(v.count);
    for (std::size_t i = 0; i < v.count; ++i) {
      std::array<float, N> f;
      std::memcpy(f.data(), v.data + i * v.stride, sizeof f);
      for (const float value : f)
        if (!std::isfinite(value))
          source_.fail(at("accessors", index), "holds a value that is not a finite number");
      out[i] = make(f);
    }
    return out;
  }

  std::vector<Vec3> vec3s(int index, const std::string& from) const {
    return floats<3, Vec3>(index, TINYGLTF_TYPE_VEC3, from,
                           [](const std::array<float, 3>& f) { return Vec3(f[0], f[1], f[2]); });
  }

  // TEXCOORD_0, its v turned to run up the image as Mesh::uvs has it (glTF's runs down).
  std::vector<Uv> uvs(int index, const std::string& from) const {
    return floats<2, Uv>(index, TINYGLTF_TYPE_VEC2, from,
                         [](const std::array<float, 2>& f) { return Uv(f[0], 1.0f - f[1]); });
  }

  // The texture of a material's textureInfo, if it has one: `pointer` is the textureInfo's.
  std::optional<TexturedColor> texture(const tinygltf::TextureInfo& info, const Color& scale,
                                       const std::string& pointer) const {
    if (info.index < 0) return std::nullopt;
    if (static_cast<std::size_t>(info.index) >= gltf_.textures.size())
      source_.fail(pointer + "/index", "names a texture that does not exist");
    if (info.texCoord != 0)
      source_.fail(pointer + "/texCoord", "only TEXCOORD_0 is read; this names another set");
    const tinygltf::Texture& texture = gltf_.textures[info.index];
    const std::string texture_pointer = at("textures", info.index);
    if (texture.source < 0 || static_cast<std::size_t>(texture.source) >= gltf_.images.size())
      source_.fail(texture_pointer + "/source", "must name an image");
    const std::size_t image = texture.source;
    if (image >= images_.size() || !images_[image])
      source_.fail(at("images", image), "has no bytes that could be read");
    TexturedColor out;
    const tinygltf::Image& info_image = gltf_.images[image];
    out.image.name = source_.name + ":" + at("images", image);
    out.image.bytes = images_[image];
    out.image.extension = info_image.mimeType == "image/jpeg" ? ".jpg"
                          : info_image.mimeType == "image/png"
                              ? ".png"
                              : std::filesystem::path(info_image.uri).extension().string();
    out.scale = scale;
    if (texture.sampler >= 0 && static_cast<std::size_t>(texture.sampler) < gltf_.samplers.size()) {
      const int wrap = gltf_.samplers[texture.sampler].wrapS;
      out.wrap = wrap == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE     ? TextureWrap::clamp
                 : wrap == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? TextureWrap::mirror
                                                                 : TextureWrap::repeat;
    }
    return out;
  }

  // The material of a primitive, with its base colour and emissive textures: the base
  // colour's colours K_D and K_A, as its factor does (docs/scene-format.md).
  Material material(int index) const {
    const tinygltf::Material& file_material = gltf_.materials[index];
    Material m = gltf_material(file_material);
    const std::string pointer = at("materials", index);
    const auto& pbr = file_material.pbrMetallicRoughness;
    if (auto base = texture(pbr.baseColorTexture, m.diffuse,
                            pointer + "/pbrMetallicRoughness/baseColorTexture")) {
      m.texture(TexturedTerm::diffuse) = *base;
      base->scale = m.ambient;
      m.texture(TexturedTerm::ambient) = std::move(*base);
    }
    m.texture(TexturedTerm::emission) =
        texture(file_material.emissiveTexture, m.emission, pointer + "/emissiveTexture");
    return m;
  }

  std::vector<std::uint32_t> indices(int index, std::size_t vertices,
                                     const std::string& from) const {
    const AccessorView v = view(index, TINYGLTF_TYPE_SCALAR, 1, true, from);
    std::vector<std::uint32_t> out(v.count);
    for (std::size_t i = 0; i < v.count; ++i) {
      const unsigned char* p = v.data + i * v.stride;
      std::uint32_t value = 0;
      if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
        value = *p;
      } else if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
        std::uint16_t s;
        std::memcpy(&s, p, 2);
        value = s;
      } else {
        std::memcpy(&value, p, 4);
      }
      if (value >= vertices)
        source_.fail(at("accessors", index), "index " + std::to_string(value) +
                                                 " is not below the primitive's " +
                                                 std::to_string(vertices) + " vertices");
      out[i] = value;
    }
    return out;
  }

  void primitive(std::size_t mesh, std::size_t p, const Mat4& world, Model& model) {
    const tinygltf::Primitive& primitive = gltf_.meshes[mesh].primitives[p];
    const std::string pointer = at("meshes", mesh) + "/primitives/" + std::to_string(p);
    const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        mode != TINYGLTF_MODE_TRIANGLE_FAN)
      return;  // points and lines have no surface to hit
    const auto position = primitive.attributes.find("POSITION");
    if (position == primitive.attributes.end())
      source_.fail(pointer + "/attributes", "has no POSITION");
    RawMesh raw;
    raw.positions = vec3s(position->second, pointer + "/attributes/POSITION");
    if (const auto normal = primitive.attributes.find("NORMAL");
        normal != primitive.attributes.end() && source_.request->normals == NormalsMode::file) {
      raw.normals = vec3s(normal->second, pointer + "/attributes/NORMAL");
      if (raw.normals.size() != raw.positions.size())
        source_.fail(at("accessors", normal->second), "must have as many normals as positions");
    }
    if (const auto uv = primitive.attributes.find("TEXCOORD_0"); uv != primitive.attributes.end()) {
      raw.uvs = uvs(uv->second, pointer + "/attributes/TEXCOORD_0");
      if (raw.uvs.size() != raw.positions.size())
        source_.fail(at("accessors", uv->second), "must have as many uvs as positions");
    }
    std::vector<std::uint32_t> order;
    if (primitive.indices >= 0) {
      order = indices(primitive.indices, raw.positions.size(), pointer + "/indices");
    } else {
      order.resize(raw.positions.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    }
    add_triangles(order, mode, raw.triangles);
    triangles_ += raw.triangles.size();
    if (triangles_ > source_.request->max_triangles) source_.fail_triangles(pointer, triangles_);
    place(world, raw);
    auto mesh_out = finish_mesh(std::move(raw), source_.request->normals);
    if (!mesh_out) return;
    ModelPart part{std::move(*mesh_out), std::nullopt, gltf_.meshes[mesh].name};
    if (primitive.material >= 0 &&
        static_cast<std::size_t>(primitive.material) < gltf_.materials.size())
      part.material = material(primitive.material);
    else if (primitive.material >= 0)
      source_.fail(pointer + "/material", "names a material that does not exist");
    model.parts.push_back(std::move(part));
  }

  void node(int index, const Mat4& parent, int depth, Model& model) {
    if (index < 0 || static_cast<std::size_t>(index) >= gltf_.nodes.size())
      source_.fail("/nodes", "a node " + std::to_string(index) + " is named that does not exist");
    // Nodes form trees: a node reached twice has two parents, or is its own ancestor, and
    // walking on could take exponential time.
    if (visited_.empty()) visited_.resize(gltf_.nodes.size(), false);
    if (visited_[index])
      source_.fail(at("nodes", index), "is reached twice: the node hierarchy must be a tree");
    visited_[index] = true;
    if (depth > max_depth)
      source_.fail(at("nodes", index),
                   "is nested more than " + std::to_string(max_depth) + " levels deep");
    const tinygltf::Node& n = gltf_.nodes[index];
    const Mat4 world = parent * local_matrix(n);
    if (n.mesh >= 0) {
      if (static_cast<std::size_t>(n.mesh) >= gltf_.meshes.size())
        source_.fail(at("nodes", index) + "/mesh", "names a mesh that does not exist");
      for (std::size_t p = 0; p < gltf_.meshes[n.mesh].primitives.size(); ++p)
        primitive(n.mesh, p, world, model);
    }
    for (const int child : n.children) node(child, world, depth + 1, model);
  }

  std::vector<int> roots() const {
    if (!gltf_.scenes.empty()) {
      const std::size_t scene = gltf_.defaultScene >= 0 ? gltf_.defaultScene : 0;
      if (scene >= gltf_.scenes.size()) source_.fail("/scene", "names a scene that does not exist");
      return gltf_.scenes[scene].nodes;
    }
    // No scene: every node no other node names as a child.
    std::vector<bool> child(gltf_.nodes.size(), false);
    for (const tinygltf::Node& n : gltf_.nodes)
      for (const int c : n.children)
        if (c >= 0 && static_cast<std::size_t>(c) < child.size()) child[c] = true;
    std::vector<int> result;
    for (std::size_t i = 0; i < child.size(); ++i)
      if (!child[i]) result.push_back(static_cast<int>(i));
    return result;
  }

 private:
  static Mat4 local_matrix(const tinygltf::Node& n) {
    if (n.matrix.size() == 16) {
      Mat4 m;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m[c][r] = n.matrix[4 * c + r];  // column-major, as glm
      return m;
    }
    Mat4 m(1.0);
    if (n.translation.size() == 3)
      m[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
    if (n.rotation.size() == 4)
      m = m *
          glm::mat4_cast(glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]));
    if (n.scale.size() == 3)
      m = m * glm::scale(Mat4(1.0), Vec3(n.scale[0], n.scale[1], n.scale[2]));
    return m;
  }

  // glTF keeps triangles counter-clockwise in the node's space; a mirroring transform turns
  // them clockwise, so they are turned back.
  static void place(const Mat4& world, RawMesh& raw) {
    const glm::dmat3 linear(world);
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    for (Vec3& p : raw.positions) p = Vec3(world * glm::dvec4(p, 1.0));
    for (Vec3& n : raw.normals) n = normal_matrix * n;
    if (glm::determinant(linear) < 0)
      for (auto& t : raw.triangles) std::swap(t[1], t[2]);
  }

  static void add_triangles(const std::vector<std::uint32_t>& order, int mode,
                            std::vector<std::array<std::uint32_t, 3>>& out) {
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      for (std::size_t i = 0; i + 2 < order.size(); i += 3)
        out.push_back({order[i], order[i + 1], order[i + 2]});
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      // Every other triangle of a strip is wound the other way; the spec's order keeps all
      // counter-clockwise.
      for (std::size_t i = 0; i + 2 < order.size(); ++i)
        out.push_back(i % 2 == 0 ? std::array{order[i], order[i + 1], order[i + 2]}
                                 : std::array{order[i + 1], order[i], order[i + 2]});
    } else {
      for (std::size_t i = 1; i + 1 < order.size(); ++i)
        out.push_back({order[i], order[i + 1], order[0]});
    }
  }

  static constexpr int max_depth = 1000;
  const tinygltf::Model& gltf_;
  const ModelSource& source_;
  const std::vector<std::shared_ptr<const std::string>>& images_;
  std::size_t triangles_ = 0;
  std::vector<bool> visited_;
};

double number_in(const tinygltf::ExtensionMap& extensions, const std::string& extension,
                 const std::string& key, double fallback) {
  const auto found = extensions.find(extension);
  if (found == extensions.end() || !found->second.Has(key)) return fallback;
  const tinygltf::Value& value = found->second.Get(key);
  return value.IsNumber() ? value.GetNumberAsDouble() : fallback;
}

Color rgb(const std::vector<double>& values, const Color& fallback) {
  if (values.size() < 3) return fallback;
  const Color c(values[0], values[1], values[2]);
  const bool finite = std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
  return finite ? glm::max(c, Color(0.0)) : fallback;
}

}  // namespace

Material gltf_material(const tinygltf::Material& material) {
  const auto& pbr = material.pbrMetallicRoughness;
  const Color base = rgb(pbr.baseColorFactor, Color(1.0));
  const double metallic = std::clamp(pbr.metallicFactor, 0.0, 1.0);
  const double roughness = std::clamp(pbr.roughnessFactor, 0.0, 1.0);
  const auto& ext = material.extensions;
  const double transmission =
      std::clamp(number_in(ext, "KHR_materials_transmission", "transmissionFactor", 0.0), 0.0, 1.0);
  double ior = number_in(ext, "KHR_materials_ior", "ior", 1.5);
  if (!(ior >= 1.0) || !std::isfinite(ior)) ior = 1.5;
  const double strength =
      std::max(number_in(ext, "KHR_materials_emissive_strength", "emissiveStrength", 1.0), 0.0);

  const double f0 = ((ior - 1) / (ior + 1)) * ((ior - 1) / (ior + 1));
  const Color specular = glm::mix(Color(f0), base, metallic);
  const double alpha = std::max(roughness * roughness, 1e-2);
  Material m;
  m.diffuse = (1.0 - metallic) * (1.0 - transmission) * base;
  m.ambient = m.diffuse;
  m.specular = specular;
  m.shininess = std::min(2.0 / (alpha * alpha) - 2.0, 10000.0);
  m.reflection = specular * (1.0 - roughness) * (1.0 - roughness);
  m.transmission = (1.0 - metallic) * transmission * base;
  m.ior = ior;
  m.emission = rgb(material.emissiveFactor, Color(0.0)) * strength;
  return m;
}

Model gltf_model(const tinygltf::Model& gltf, const ModelSource& source,
                 const std::vector<std::shared_ptr<const std::string>>& images) {
  GltfReader reader(gltf, source, images);
  Model model;
  for (const int root : reader.roots()) reader.node(root, Mat4(1.0), 0, model);
  return model;
}

}  // namespace tessera
