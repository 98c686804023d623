// Scenes that name mesh files: what the parser makes of them, and its errors.
#include <set>

#include <gmock/gmock.h>
#include <nlohmann/json.hpp>

#include "common/scene/scene_parser.hpp"
#include "mesh_file_support.hpp"

namespace tessera {
namespace {

using ::testing::HasSubstr;

constexpr std::string_view tetra_off =
    "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
    "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

constexpr std::string_view two_materials_obj = R"(mtllib m.mtl
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
usemtl a
f 1 2 3
usemtl b
f 1 2 4
)";
constexpr std::string_view two_materials_mtl = "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 1 0\n";

class MeshFileSceneTest : public test::MeshFileTest {
 protected:
  Scene parse(const nlohmann::json& objects, const Limits& limits = {}) {
    nlohmann::json scene = {{"image", {{"width", 8}, {"height", 8}}},
                            {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}}},
                            {"objects", objects}};
    const FolderSceneFiles files(dir_);
    return parse_scene_text(scene.dump(), limits, {}, &files);
  }
  SceneError parse_error(const nlohmann::json& objects, const Limits& limits = {}) {
    try {
      parse(objects, limits);
    } catch (const SceneError& e) {
      return e;
    }
    ADD_FAILURE() << "no error";
    return SceneError("", "");
  }
};

TEST_F(MeshFileSceneTest, AFileIsAMeshWithTheObjectsMaterialAndTransform) {
  write("models/tetra.off", tetra_off);
  const Scene scene = parse(nlohmann::json::parse(R"([
    {"type": "mesh", "file": "models/tetra.off", "material": {"diffuse": [0, 0, 1]},
     "transform": [{"translate": [1, 2, 3]}], "normals": "smooth"}])"));
  ASSERT_EQ(scene.objects.size(), 1u);
  const Object& object = scene.objects[0];
  const Mesh& mesh = std::get<Mesh>(object.shape);
  EXPECT_EQ(mesh.triangles.size(), 4u);
  EXPECT_EQ(mesh.normals.size(), 4u);
  EXPECT_TRUE(is_solid(object));
  EXPECT_EQ(scene.materials[object.material].diffuse, Color(0, 0, 1));
  EXPECT_EQ(object.transform[3], glm::dvec4(1, 2, 3, 1));
}

TEST_F(MeshFileSceneTest, EachFileMaterialBecomesAPartUnlessTheObjectNamesOne) {
  write("m.mtl", two_materials_mtl);
  write("two.obj", two_materials_obj);
  const Scene own = parse(nlohmann::json::parse(R"([{"type": "mesh", "file": "two.obj"}])"));
  ASSERT_EQ(own.objects.size(), 2u);
  EXPECT_EQ(own.materials[own.objects[0].material].diffuse, Color(1, 0, 0));
  EXPECT_EQ(own.materials[own.objects[1].material].diffuse, Color(0, 1, 0));
  const Scene overridden = parse(nlohmann::json::parse(
      R"([{"type": "mesh", "file": "two.obj", "material": {"diffuse": 0.5}, "thin": true}])"));
  ASSERT_EQ(overridden.objects.size(), 2u);
  EXPECT_EQ(overridden.objects[0].material, overridden.objects[1].material);
  EXPECT_FALSE(is_solid(overridden.objects[1]));
  EXPECT_EQ(overridden.materials.size(), 2u);  // the default and the object's: none of the file's
}

TEST_F(MeshFileSceneTest, ErrorsPointAtTheObjectAndNameTheFile) {
  write("tetra.off", tetra_off);
  SceneError missing = parse_error({{{"type", "mesh"}, {"file", "nowhere.obj"}}});
  EXPECT_EQ(missing.pointer(), "/objects/0/file");
  EXPECT_THAT(missing.detail(), HasSubstr("nowhere.obj: cannot open"));

  write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  SceneError bad = parse_error(
      {{{"type", "mesh"}, {"file", "tetra.off"}}, {{"type", "mesh"}, {"file", "bad.off"}}});
  EXPECT_EQ(bad.pointer(), "/objects/1/file");
  EXPECT_THAT(bad.detail(), HasSubstr("bad.off:line 6: vertex index \"7\""));

  EXPECT_EQ(parse_error({{{"type", "mesh"}, {"file", "tetra.stl"}}}).pointer(), "/objects/0/file");
  EXPECT_EQ(parse_error({{{"type", "mesh"}, {"file", "tetra.off"}, {"format", "stl"}}}).pointer(),
            "/objects/0/format");
  EXPECT_EQ(
      parse_error({{{"type", "mesh"}, {"file", "tetra.off"}, {"normals", "bumpy"}}}).pointer(),
      "/objects/0/normals");
  EXPECT_EQ(parse_error({{{"type", "mesh"}, {"file", "tetra.off"}, {"positions", {}}}}).pointer(),
            "/objects/0/positions");
  // A format by name for a file whose extension says nothing.
  write("tetra.mesh", tetra_off);
  EXPECT_EQ(parse({{{"type", "mesh"}, {"file", "tetra.mesh"}, {"format", "off"}}}).objects.size(),
            1u);
}

TEST_F(MeshFileSceneTest, FileTrianglesCountAgainstTheScenesLimit) {
  write("tetra.off", tetra_off);
  Limits limits;
  limits.max_triangles = 6;
  // One tetrahedron (4) fits in 6; a second does not.
  const nlohmann::json one = {{"type", "mesh"}, {"file", "tetra.off"}};
  EXPECT_EQ(parse(nlohmann::json::array({one}), limits).objects.size(), 1u);
  const SceneError over = parse_error(nlohmann::json::array({one, one}), limits);
  EXPECT_EQ(over.pointer(), "/objects/1/file");
  EXPECT_EQ(over.limit(), "max_triangles");
  EXPECT_THAT(over.detail(), HasSubstr("needs at least 4 triangles, more than the scene's "
                                       "remaining 2 of 6"));
}

TEST_F(MeshFileSceneTest, WithoutFilesAMeshFileIsRefused) {
  nlohmann::json scene = {{"image", {{"width", 8}, {"height", 8}}},
                          {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}}},
                          {"objects", {{{"type", "mesh"}, {"file", "tetra.off"}}}}};
  try {
    parse_scene(scene);
    FAIL() << "read a mesh file with no SceneFiles";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.pointer(), "/objects/0/file");
    EXPECT_THAT(e.detail(), HasSubstr("which this reader of the scene cannot open"));
  }
}

// The farm's form: the model and its MTL are assets, found by digest.
TEST_F(MeshFileSceneTest, AssetsAreFoundByDigestAndTheirFilesThroughTheirMap) {
  const std::string obj_digest(64, 'a'), mtl_digest(64, 'b');
  write("store/" + obj_digest, two_materials_obj);
  write("store/" + mtl_digest, two_materials_mtl);
  std::set<std::string> held = {obj_digest, mtl_digest};
  const AssetSceneFiles files(
      [&](const std::string& digest) -> std::optional<std::filesystem::path> {
        if (!held.contains(digest)) return std::nullopt;
        return dir_ / "store" / digest;
      });
  nlohmann::json object = {{"type", "mesh"},
                           {"asset", "sha256:" + obj_digest},
                           {"format", "obj"},
                           {"name", "two.obj"},
                           {"files", {{"m.mtl", "sha256:" + mtl_digest}}}};
  const auto parse_with = [&](const nlohmann::json& o) {
    nlohmann::json scene = {{"image", {{"width", 8}, {"height", 8}}},
                            {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}}},
                            {"objects", {o}}};
    return parse_scene_text(scene.dump(), {}, {}, &files);
  };
  const Scene scene = parse_with(object);
  ASSERT_EQ(scene.objects.size(), 2u);
  EXPECT_EQ(scene.materials[scene.objects[1].material].diffuse, Color(0, 1, 0));

  held.erase(mtl_digest);
  try {
    parse_with(object);
    FAIL() << "a missing MTL asset was not noticed";
  } catch (const MissingAssetError& e) {
    EXPECT_EQ(e.pointer(), "/objects/0/files/m.mtl");
    EXPECT_EQ(e.digest(), mtl_digest);
  }
  held.erase(obj_digest);
  try {
    parse_with(object);
    FAIL() << "a missing model asset was not noticed";
  } catch (const MissingAssetError& e) {
    EXPECT_EQ(e.pointer(), "/objects/0/asset");
  }
  held = {obj_digest, mtl_digest};
  object["files"] = nlohmann::json::object();
  try {
    parse_with(object);
    FAIL() << "an MTL the map does not name was read";
  } catch (const SceneError& e) {
    EXPECT_THAT(e.detail(),
                HasSubstr("two.obj:line 1: names \"m.mtl\", which the scene's \"files\""));
  }
  object["asset"] = "sha256:ABC";
  try {
    parse_with(object);
    FAIL() << "a malformed digest was taken";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.pointer(), "/objects/0/asset");
  }
}

}  // namespace
}  // namespace tessera
