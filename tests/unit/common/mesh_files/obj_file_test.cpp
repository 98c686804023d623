#include <gmock/gmock.h>

#include "mesh_file_support.hpp"

namespace tessera {
namespace {

using ::testing::HasSubstr;

constexpr std::string_view mtl = R"(# two materials
newmtl red
Ka 0.1 0 0
Kd 0.8 0 0
Ks 0.5 0.5 0.5
Ns 40
illum 2

newmtl glass
Kd 0.2 0.2 0.2
Ks 1 1 1
Ns 200
Ni 1.5
d 0.25
Tf 0.8 1 1
Ke 0.1 0.2 0.3
illum 4
)";

// A quad and a pentagon, in two groups and two materials, with relative indices.
constexpr std::string_view two_parts = R"(mtllib parts.mtl
o first
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
g quad
usemtl red
f 1 2 3 4
o second
v 0 0 1
v 1 0 1
v 1.5 0.5 1
v 1 1 1
v 0 1 1
g pentagon
usemtl glass
f -5 -4 -3 -2 -1
)";

class ObjFileTest : public test::MeshFileTest {};

TEST_F(ObjFileTest, PolygonsRelativeIndicesAndOnePartPerMaterial) {
  write("parts.mtl", mtl);
  write("parts.obj", two_parts);
  const Model model = load("parts.obj");
  ASSERT_EQ(model.parts.size(), 2u);
  EXPECT_EQ(model.parts[0].name, "red");
  EXPECT_EQ(model.parts[0].mesh.triangles.size(), 2u);
  EXPECT_EQ(model.parts[1].name, "glass");
  EXPECT_EQ(model.parts[1].mesh.triangles.size(), 3u);
  EXPECT_EQ(model.parts[1].mesh.positions[0], Vec3(0, 0, 1));
  EXPECT_TRUE(model.parts[0].mesh.normals.empty());
}

TEST_F(ObjFileTest, MtlTermsMapToTheSeedModel) {
  write("parts.mtl", mtl);
  write("parts.obj", two_parts);
  const Model model = load("parts.obj");
  const Material& red = *model.parts[0].material;
  EXPECT_NEAR(red.ambient.r, 0.1, 1e-7);
  EXPECT_NEAR(red.diffuse.r, 0.8, 1e-7);
  EXPECT_NEAR(red.specular.g, 0.5, 1e-7);
  EXPECT_EQ(red.shininess, 40.0);
  EXPECT_EQ(red.reflection, Color(0.0));  // illum 2: highlights, no mirror
  EXPECT_EQ(red.transmission, Color(0.0));

  const Material& glass = *model.parts[1].material;
  EXPECT_NEAR(glass.ior, 1.5, 1e-7);
  EXPECT_NEAR(glass.reflection.r, 1.0, 1e-7);  // illum 4: reflection on
  // d 0.25: three quarters pass, through the filter Tf; what is left of K_D is a quarter.
  EXPECT_NEAR(glass.transmission.r, 0.75 * 0.8, 1e-6);
  EXPECT_NEAR(glass.transmission.g, 0.75, 1e-6);
  EXPECT_NEAR(glass.diffuse.r, 0.25 * 0.2, 1e-6);
  EXPECT_NEAR(glass.emission.b, 0.3, 1e-7);
}

TEST_F(ObjFileTest, FileNormalsWhereEveryFaceHasThem) {
  write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 0 1 1\nf 1//1 2//1 3//2\n");
  const Mesh mesh = load("n.obj").parts[0].mesh;
  ASSERT_EQ(mesh.normals.size(), 3u);
  EXPECT_EQ(mesh.normals[0], Vec3(0, 0, 1));
  EXPECT_NEAR(glm::length(mesh.normals[2] - glm::normalize(Vec3(0, 1, 1))), 0.0, 1e-7);
  // One face without: the part is shaded flat.
  write("some.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 2 4 3\n");
  EXPECT_TRUE(load("some.obj").parts[0].mesh.normals.empty());
}

TEST_F(ObjFileTest, TheSameCornerWithTwoNormalsBecomesTwoPositions) {
  write("crease.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 0 1 0\nf 1//1 2//1 3//1\nf 2//2 1//2 "
        "4//2\n");
  const Mesh file = load("crease.obj").parts[0].mesh;
  EXPECT_EQ(file.positions.size(), 6u);
  const Mesh smooth = load("crease.obj", NormalsMode::smooth).parts[0].mesh;
  EXPECT_EQ(smooth.positions.size(), 4u);
}

TEST_F(ObjFileTest, ErrorsNameTheLine) {
  write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nf 1 2 9\n");
  EXPECT_THAT(
      load_error("range.obj"),
      HasSubstr("range.obj:line 6: a face names a vertex, uv or normal that does not exist"));
  write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  EXPECT_THAT(load_error("zero.obj"), HasSubstr("zero.obj:line 4: "));
  write("points.obj", "v 0 0 0\nv 1 0 0\n");
  EXPECT_THAT(load_error("points.obj"), HasSubstr("points.obj: has no triangles"));
}

TEST_F(ObjFileTest, AMaterialLibraryOutsideTheModelsFolderIsRefused) {
  write("secret.mtl", mtl);
  write("models/escape.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\n# comment\nmtllib ../secret.mtl\nf 1 2 3\n");
  EXPECT_EQ(load_error("models/escape.obj"),
            "models/escape.obj:line 5: names \"../secret.mtl\", which is outside the model's own "
            "folder; a model's files must sit beside it or below it");
  write("models/absolute.obj", "mtllib /etc/passwd\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_THAT(load_error("models/absolute.obj"), HasSubstr("outside the model's own folder"));
}

TEST_F(ObjFileTest, TrianglesOverTheLimitAreRefusedAtTheFaceThatCrossesIt) {
  write("many.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\nf 1 2 4\n");
  try {
    load("many.obj", NormalsMode::file, 2);
    FAIL() << "three triangles were read under a limit of two";
  } catch (const SceneFileError& e) {
    EXPECT_EQ(e.limit(), "max_triangles");
    EXPECT_THAT(e.what(), HasSubstr("many.obj:line 7: needs at least 3 triangles"));
  }
}

TEST_F(ObjFileTest, UvsSplitCornersAtSeamsAndMapsBecomeTextures) {
  write("tex/wood.png", "png bytes: the reader only locates the file");
  write("box.mtl", "newmtl wood\nKa 0.5 0.5 0.5\nKd 0.8 0.6 0.4\nmap_Kd -clamp on tex/wood.png\n");
  // Two triangles sharing the edge 1-3, whose corner 3 has a different uv in each: a seam.
  write("box.obj", R"(mtllib box.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vt 0.5 0.5
usemtl wood
f 1/1 2/2 3/3
f 1/1 3/5 4/4
)");
  const Model model = load("box.obj", NormalsMode::smooth);
  ASSERT_EQ(model.parts.size(), 1u);
  const Mesh& mesh = model.parts[0].mesh;
  ASSERT_EQ(mesh.positions.size(), 5u);  // corner 3 twice, once per uv
  ASSERT_EQ(mesh.uvs.size(), 5u);
  EXPECT_EQ(mesh.uvs[mesh.triangles[1][1]], Uv(0.5f, 0.5f));
  EXPECT_EQ(mesh.uvs[mesh.triangles[0][2]], Uv(1.0f, 1.0f));
  // The seam does not crease the smooth normals: both copies of corner 3 face +z.
  EXPECT_EQ(mesh.normals[mesh.triangles[1][1]], mesh.normals[mesh.triangles[0][2]]);
  const Material& wood = *model.parts[0].material;
  ASSERT_TRUE(wood.texture(TexturedTerm::diffuse));
  const TexturedColor& kd = *wood.texture(TexturedTerm::diffuse);
  EXPECT_EQ(kd.image.name, "tex/wood.png");
  EXPECT_EQ(std::filesystem::path(kd.image.path), dir_ / "tex/wood.png");
  EXPECT_EQ(kd.scale, Color(0.8f, 0.6f, 0.4f));  // as the MTL's floats
  EXPECT_EQ(kd.wrap, TextureWrap::clamp);
  // With no map_Ka, map_Kd colours K_A too, scaled by Ka.
  ASSERT_TRUE(wood.texture(TexturedTerm::ambient));
  EXPECT_EQ(wood.texture(TexturedTerm::ambient)->scale, Color(0.5f));
  EXPECT_FALSE(wood.texture(TexturedTerm::specular));
}

TEST_F(ObjFileTest, AMissingOrEscapingTextureIsAnError) {
  write("a.obj", "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n");
  write("a.mtl", "newmtl m\nmap_Kd gone.png\n");
  EXPECT_THAT(load_error("a.obj"), HasSubstr("gone.png"));
  write("a.mtl", "newmtl m\nmap_Kd ../../etc/passwd\n");
  EXPECT_THAT(load_error("a.obj"), HasSubstr("outside the model's own folder"));
}

TEST_F(ObjFileTest, AFaceNamingAMissingUvNamesItsLine) {
  write("a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n");
  EXPECT_THAT(load_error("a.obj"), HasSubstr("a.obj:line 5"));
}

}  // namespace
}  // namespace tessera
