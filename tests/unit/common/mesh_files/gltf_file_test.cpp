#include <array>
#include <cstring>

#include <gmock/gmock.h>
#include <nlohmann/json.hpp>

#include "examples/gltf_bytes.hpp"
#include "mesh_file_support.hpp"

namespace tessera {
namespace {

using gltf_bytes::append;
using gltf_bytes::base64;
using ::testing::HasSubstr;

// A unit square as two triangles: four float positions, then six 16-bit indices.
std::string square_buffer(std::array<std::uint16_t, 6> indices = {0, 1, 2, 0, 2, 3}) {
  std::string bytes;
  for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f})
    append(bytes, v);
  for (const std::uint16_t i : indices) append(bytes, i);
  return bytes;
}

// Every triangle faces +z, as the square does: none was turned over.
void expect_facing_z(const Mesh& mesh) {
  for (const auto& t : mesh.triangles) {
    const Vec3 n = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                              mesh.positions[t[2]] - mesh.positions[t[0]]);
    EXPECT_GT(n.z, 0.0);
  }
}

nlohmann::json square_gltf(const std::string& uri) {
  return nlohmann::json::parse(R"({
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"translation": [10, 0, 0], "children": [1]}, {"scale": [2, 2, 2], "mesh": 0}],
    "meshes": [{"name": "square", "primitives": [
      {"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
    "materials": [{
      "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0,
                               "roughnessFactor": 0.5},
      "emissiveFactor": [0.25, 0, 0],
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5},
                     "KHR_materials_ior": {"ior": 2.0},
                     "KHR_materials_emissive_strength": {"emissiveStrength": 4}}}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
       "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                    {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
    "buffers": [{"byteLength": 60}]
  })")
      .patch(nlohmann::json::array({{{"op", "add"}, {"path", "/buffers/0/uri"}, {"value", uri}}}));
}

class GltfFileTest : public test::MeshFileTest {};

TEST_F(GltfFileTest, NodeTransformsComposeDownTheHierarchy) {
  write("square.gltf",
        square_gltf("data:application/octet-stream;base64," + base64(square_buffer())).dump());
  const Model model = load("square.gltf");
  ASSERT_EQ(model.parts.size(), 1u);
  const Mesh& mesh = model.parts[0].mesh;
  EXPECT_EQ(model.parts[0].name, "square");
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.positions, (std::vector<Vec3>{{10, 0, 0}, {12, 0, 0}, {12, 2, 0}, {10, 2, 0}}));
}

TEST_F(GltfFileTest, MetallicRoughnessAndTheKhrExtensionsMapToTheSeedModel) {
  write("square.gltf",
        square_gltf("data:application/octet-stream;base64," + base64(square_buffer())).dump());
  const Material m = *load("square.gltf").parts[0].material;
  const double f0 = 1.0 / 9.0;  // ((ior - 1) / (ior + 1))^2 at ior 2
  EXPECT_NEAR(m.specular.r, f0, 1e-12);
  EXPECT_NEAR(m.diffuse.r, 0.5 * 0.5, 1e-12);  // (1 - metallic)(1 - transmission) base
  EXPECT_EQ(m.ambient, m.diffuse);
  EXPECT_NEAR(m.transmission.r, 0.25, 1e-12);
  EXPECT_EQ(m.ior, 2.0);
  EXPECT_NEAR(m.shininess, 30.0, 1e-9);           // 2 / alpha^2 - 2, alpha = roughness^2
  EXPECT_NEAR(m.reflection.r, f0 * 0.25, 1e-12);  // F0 (1 - roughness)^2
  EXPECT_EQ(m.emission, Color(1.0, 0.0, 0.0));    // 0.25 x strength 4
}

TEST_F(GltfFileTest, AnExternalBinBesideTheModelAndNotOutsideIt) {
  write("models/mesh.bin", square_buffer());
  write("models/square.gltf", square_gltf("mesh.bin").dump());
  EXPECT_EQ(load("models/square.gltf").parts[0].mesh.triangles.size(), 2u);
  write("secret.bin", square_buffer());
  write("models/escape.gltf", square_gltf("../secret.bin").dump());
  EXPECT_THAT(load_error("models/escape.gltf"),
              HasSubstr("names \"../secret.bin\", which is outside the model's own folder"));
}

TEST_F(GltfFileTest, StripsAndFansBecomeCounterClockwiseTriangles) {
  nlohmann::json gltf =
      square_gltf("data:application/octet-stream;base64," + base64(square_buffer()));
  auto& primitive = gltf["meshes"][0]["primitives"][0];
  primitive.erase("indices");
  primitive["mode"] = 6;  // a fan around vertex 0: (1 2 0), (2 3 0)
  write("fan.gltf", gltf.dump());
  const Mesh fan = load("fan.gltf").parts[0].mesh;
  EXPECT_EQ(fan.triangles.size(), 2u);
  expect_facing_z(fan);

  // A strip zig-zags 0 1 3 2: (0 1 3), then the second turned back to (1 2 3).
  gltf["buffers"][0]["uri"] =
      "data:application/octet-stream;base64," + base64(square_buffer({0, 1, 3, 2, 0, 0}));
  primitive["indices"] = 1;
  primitive["mode"] = 5;
  gltf["accessors"][1]["count"] = 4;
  write("strip.gltf", gltf.dump());
  const Mesh strip = load("strip.gltf").parts[0].mesh;
  EXPECT_EQ(strip.triangles.size(), 2u);
  expect_facing_z(strip);

  // A mirroring node turns the square over; its triangles are turned back.
  gltf["nodes"][1]["scale"] = {-1, 1, 1};
  write("mirror.gltf", gltf.dump());
  const Mesh mirrored = load("mirror.gltf").parts[0].mesh;
  for (const auto& t : mirrored.triangles) {
    const Vec3 n = glm::cross(mirrored.positions[t[1]] - mirrored.positions[t[0]],
                              mirrored.positions[t[2]] - mirrored.positions[t[0]]);
    EXPECT_GT(n.z, 0.0);
  }
}

// A .glb with interleaved positions and normals (stride 24) and 8-bit indices.
std::string interleaved_glb() {
  std::string bin;
  const float vertices[3][6] = {{0, 0, 0, 0, 0, 1}, {1, 0, 0, 0, 0, 1}, {0, 1, 0, 0, 0, 1}};
  for (const auto& v : vertices)
    for (const float f : v) append(bin, f);
  for (const std::uint8_t i : {0, 1, 2}) append(bin, i);
  const std::string json = nlohmann::json::parse(R"({
    "asset": {"version": "2.0"},
    "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
    "accessors": [
      {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
      {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 3, "type": "VEC3"},
      {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 72, "byteStride": 24},
                    {"buffer": 0, "byteOffset": 72, "byteLength": 3}],
    "buffers": [{"byteLength": 76}]
  })")
                               .dump();
  return gltf_bytes::glb(json, bin);
}

TEST_F(GltfFileTest, GlbWithInterleavedAttributesAndByteIndices) {
  write("tri.glb", interleaved_glb());
  const Mesh mesh = load("tri.glb").parts[0].mesh;
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.positions[2], Vec3(0, 1, 0));
  ASSERT_EQ(mesh.normals.size(), 3u);
  EXPECT_EQ(mesh.normals[1], Vec3(0, 0, 1));
}

TEST_F(GltfFileTest, ErrorsNameAJsonPointerIntoTheGltf) {
  const std::string uri = "data:application/octet-stream;base64," + base64(square_buffer());
  nlohmann::json beyond = square_gltf(uri);
  beyond["accessors"][1]["count"] = 7;  // 14 bytes from a view of 12
  write("beyond.gltf", beyond.dump());
  EXPECT_EQ(load_error("beyond.gltf"),
            "beyond.gltf:/accessors/1: reads beyond the end of its bufferView");
  nlohmann::json index = square_gltf(uri);
  index["accessors"][0]["count"] = 2;  // the indices name vertex 3
  write("index.gltf", index.dump());
  EXPECT_THAT(load_error("index.gltf"), HasSubstr("index.gltf:/accessors/1: index 2 is not below"));
  nlohmann::json cycle = square_gltf(uri);
  cycle["nodes"][1]["children"] = {0};
  write("cycle.gltf", cycle.dump());
  EXPECT_THAT(
      load_error("cycle.gltf"),
      HasSubstr("cycle.gltf:/nodes/0: is reached twice: the node hierarchy must be a tree"));
  nlohmann::json type = square_gltf(uri);
  type["accessors"][0]["componentType"] = 5123;
  write("type.gltf", type.dump());
  EXPECT_THAT(load_error("type.gltf"),
              HasSubstr("type.gltf:/accessors/0/componentType: must be FLOAT"));
  write("broken.gltf", "{\"asset\": ");
  EXPECT_THAT(load_error("broken.gltf"), HasSubstr("broken.gltf: "));
}

TEST_F(GltfFileTest, TexcoordsAndTheBaseColourAndEmissiveTextures) {
  // The square's buffer, then four uvs (glTF's v runs down the image).
  std::string buffer = square_buffer();
  for (const float v : {0.f, 1.f, 1.f, 1.f, 1.f, 0.f, 0.f, 0.f}) append(buffer, v);
  nlohmann::json gltf = square_gltf("data:application/octet-stream;base64," + base64(buffer));
  gltf["buffers"][0]["byteLength"] = buffer.size();
  gltf["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 60}, {"byteLength", 32}});
  gltf["accessors"].push_back(
      {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}});
  gltf["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2;
  gltf["images"] = {{{"uri", "data:image/png;base64," + base64("not decoded here")}},
                    {{"uri", "glow.png"}}};
  gltf["samplers"] = {{{"wrapS", 33648}, {"wrapT", 33648}}};
  gltf["textures"] = {{{"source", 0}, {"sampler", 0}}, {{"source", 1}}};
  gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  gltf["materials"][0]["emissiveTexture"] = {{"index", 1}};
  write("glow.png", "glow bytes");
  write("square.gltf", gltf.dump());
  const Model model = load("square.gltf");
  ASSERT_EQ(model.parts.size(), 1u);
  const Mesh& mesh = model.parts[0].mesh;
  ASSERT_EQ(mesh.uvs.size(), 4u);
  EXPECT_EQ(mesh.uvs[0], Uv(0.0f, 0.0f));
  EXPECT_EQ(mesh.uvs[2], Uv(1.0f, 1.0f));
  const Material& m = *model.parts[0].material;
  ASSERT_TRUE(m.texture(TexturedTerm::diffuse));
  const TexturedColor& base = *m.texture(TexturedTerm::diffuse);
  ASSERT_TRUE(base.image.bytes);
  EXPECT_EQ(*base.image.bytes, "not decoded here");
  EXPECT_EQ(base.image.extension, ".png");
  EXPECT_EQ(base.image.name, "square.gltf:/images/0");
  EXPECT_EQ(base.wrap, TextureWrap::mirror);
  EXPECT_EQ(base.scale, m.diffuse);
  ASSERT_TRUE(m.texture(TexturedTerm::ambient));  // K_A follows K_D, as its factor does
  ASSERT_TRUE(m.texture(TexturedTerm::emission));
  EXPECT_EQ(*m.texture(TexturedTerm::emission)->image.bytes, "glow bytes");
  EXPECT_EQ(m.texture(TexturedTerm::emission)->scale, m.emission);
}

TEST_F(GltfFileTest, ATextureThatNamesNoImageIsAnErrorAtItsPointer) {
  nlohmann::json gltf =
      square_gltf("data:application/octet-stream;base64," + base64(square_buffer()));
  gltf["textures"] = {{{"source", 3}}};
  gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  write("square.gltf", gltf.dump());
  EXPECT_THAT(load_error("square.gltf"), HasSubstr("/textures/0/source"));
}

TEST_F(GltfFileTest, APercentEncodedUriNamesTheDecodedFile) {
  // The name model_references() sends to the farm under (ModelReferencesTest tests it) is the
  // one the reader asks for.
  write("my mesh.bin", square_buffer());
  write("square.gltf", square_gltf("my%20mesh.bin").dump());
  EXPECT_EQ(load("square.gltf").parts.size(), 1u);
}

}  // namespace
}  // namespace tessera
