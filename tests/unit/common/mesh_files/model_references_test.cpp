// The files a model names, which travel to the farm with it (model_references.hpp).
#include <gmock/gmock.h>
#include <nlohmann/json.hpp>

#include "common/mesh_files/model_references.hpp"
#include "mesh_file_support.hpp"

namespace tessera {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

class ModelReferencesTest : public test::MeshFileTest {
 protected:
  std::vector<std::string> of(const std::string& name, MeshFormat format) {
    return model_references(dir_ / name, format, name);
  }
  std::string error_of(const std::string& name, MeshFormat format) {
    try {
      of(name, format);
    } catch (const SceneFileError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(ModelReferencesTest, AnObjNamesItsLibrariesAndTheirMapsOnce) {
  write("m/a.obj", "mtllib a.mtl lib/b.mtl\nv 0 0 0\n");
  write("m/a.mtl", "newmtl x\nmap_Kd -clamp on tex/wood.png\nmap_Ka tex/wood.png\nbump n.png\n");
  write("m/lib/b.mtl", "newmtl y\nmap_Ke ./glow.png\n");
  EXPECT_THAT(of("m/a.obj", MeshFormat::obj),
              ElementsAre("a.mtl", "lib/b.mtl", "tex/wood.png", "n.png", "glow.png"));
  write("m/a.mtl", "newmtl x\nmap_Kd ../../secret.png\n");
  EXPECT_THAT(error_of("m/a.obj", MeshFormat::obj), HasSubstr("outside the model's own folder"));
}

TEST_F(ModelReferencesTest, AGltfNamesItsBuffersAndImagesAsItsReaderDecodesTheirUris) {
  const nlohmann::json gltf = {
      {"asset", {{"version", "2.0"}}},
      {"buffers",
       {{{"uri", "data:application/octet-stream;base64,AAAA"}, {"byteLength", 3}},
        {{"uri", "my%20mesh.bin"}, {"byteLength", 3}}}},
      {"images", {{{"uri", "tex/a+b%2Bc.png"}}, {{"bufferView", 0}, {"mimeType", "image/png"}}}}};
  write("g.gltf", gltf.dump());
  // data: URIs are not files; "%20" and '+' are spaces, "%2B" a plus, as tinygltf reads them.
  EXPECT_THAT(of("g.gltf", MeshFormat::gltf), ElementsAre("my mesh.bin", "tex/a b+c.png"));
  nlohmann::json escaping = gltf;
  escaping["images"][0]["uri"] = "%2E%2E/%2E%2E/etc/passwd";
  write("g.gltf", escaping.dump());
  EXPECT_THAT(error_of("g.gltf", MeshFormat::gltf), HasSubstr("outside the model's own folder"));
}

}  // namespace
}  // namespace tessera
