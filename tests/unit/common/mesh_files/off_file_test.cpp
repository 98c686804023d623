#include <gmock/gmock.h>

#include "mesh_file_support.hpp"

namespace tessera {
namespace {

using ::testing::HasSubstr;

constexpr std::string_view cube = R"(OFF
# a unit cube, its faces as quads
8 6 12
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1   # the last corner
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 2 3 7 6
4 1 2 6 5
4 0 4 7 3 0.5 0.5 0.5
)";

class OffFileTest : public test::MeshFileTest {};

TEST_F(OffFileTest, ReadsQuadsAsTwoTrianglesEachAndSkipsCommentsAndColours) {
  write("cube.off", cube);
  const Model model = load("cube.off");
  ASSERT_EQ(model.parts.size(), 1u);
  const Mesh& mesh = model.parts[0].mesh;
  EXPECT_EQ(mesh.positions.size(), 8u);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  EXPECT_TRUE(mesh.normals.empty());
  EXPECT_FALSE(model.parts[0].material);
  // The first quad, fanned from its first corner, keeps its winding: 0 3 2, 0 2 1.
  EXPECT_EQ(mesh.triangles[0], (std::array<std::uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(mesh.positions[1], Vec3(0, 1, 0));
}

TEST_F(OffFileTest, CountsMayShareTheHeaderLineAndNoffCarriesNormals) {
  write("tri.off", "NOFF 3 1 0\n0 0 0 0 0 2\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
  const Mesh mesh = load("tri.off").parts[0].mesh;
  ASSERT_EQ(mesh.normals.size(), 3u);
  EXPECT_EQ(mesh.normals[0], Vec3(0, 0, 1));  // made unit
  EXPECT_TRUE(load("tri.off", NormalsMode::flat).parts[0].mesh.normals.empty());
}

TEST_F(OffFileTest, SmoothNormalsAverageTheFacesAroundEachCorner) {
  // Two triangles folded at a right angle along the edge 0-1.
  write("fold.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n");
  const Mesh mesh = load("fold.off", NormalsMode::smooth).parts[0].mesh;
  ASSERT_EQ(mesh.normals.size(), 4u);
  const Vec3 shared = glm::normalize(Vec3(0, 1, 1));
  EXPECT_NEAR(glm::length(mesh.normals[0] - shared), 0.0, 1e-12);
  EXPECT_NEAR(glm::length(mesh.normals[2] - Vec3(0, 0, 1)), 0.0, 1e-12);
}

TEST_F(OffFileTest, DropsDegenerateFacesAndUnusedVertices) {
  write("mess.off", "OFF\n5 2 0\n0 0 0\n1 0 0\n0 1 0\n2 0 0\n9 9 9\n3 0 1 2\n3 0 1 3\n");
  const Mesh mesh = load("mess.off").parts[0].mesh;
  EXPECT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.positions.size(), 3u);
}

TEST_F(OffFileTest, ErrorsNameTheFileAndLine) {
  write("bad_index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  EXPECT_EQ(load_error("bad_index.off"),
            "bad_index.off:line 6: vertex index \"3\" must be below the 3 vertices");
  write("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n# the file ends here\n");
  EXPECT_THAT(load_error("short.off"), HasSubstr("short.off:line 5: ends after 2 of 3 vertices"));
  write("word.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_error("word.off"),
            "word.off:line 4: coordinate 2 must be a finite number, got \"zero\"");
  write("face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
  EXPECT_THAT(load_error("face.off"), HasSubstr("face.off:line 6: a face is"));
  write("empty.off", "# nothing\n");
  EXPECT_THAT(load_error("empty.off"), HasSubstr("empty.off: is empty"));
  EXPECT_THAT(load_error("missing.off"), HasSubstr("missing.off: cannot open"));
}

TEST_F(OffFileTest, HugeCountsAreRefusedBeforeAnythingIsAllocated) {
  // 2^31 vertices in a file of a few bytes: refused from the counts line, at once.
  write("huge.off", "OFF\n2147483648 1 0\n0 0 0\n");
  EXPECT_THAT(load_error("huge.off"),
              HasSubstr("huge.off:line 2: claims 2147483648 vertices and 1 faces, more than"));
  write("many.off", std::string("OFF\n3 2147483648 0\n") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  try {
    load("many.off", NormalsMode::file, 1000);
    FAIL() << "a file of 2^31 faces was read";
  } catch (const SceneFileError& e) {
    EXPECT_EQ(e.limit(), "max_triangles");
    EXPECT_THAT(
        e.what(),
        HasSubstr("needs at least 2147483648 triangles, more than the scene's remaining 1000"));
  }
}

}  // namespace
}  // namespace tessera
