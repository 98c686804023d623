#include <bit>
#include <cstring>
#include <limits>

#include <gmock/gmock.h>

#include "mesh_file_support.hpp"

namespace tessera {
namespace {

using ::testing::HasSubstr;

constexpr std::string_view ascii_quad = R"(ply
format ascii 1.0
comment a unit square as one quad, then one triangle beside it
element vertex 5
property float x
property float y
property float z
property float nx
property float ny
property float nz
element face 2
property list uchar int vertex_indices
element edge 1
property int vertex1
property int vertex2
end_header
0 0 0 0 0 1
1 0 0 0 0 1
1 1 0 0 0 1
0 1 0 0 0 1
2 0 0 0 0 1
4 0 1 2 3
3 1 4 2
0 1
)";

class PlyFileTest : public test::MeshFileTest {
 protected:
  // The same model as ascii_quad, in binary of the given byte order; the face element has an
  // extra uchar "flags" property to skip.
  std::string binary(bool big_endian) {
    std::string header =
        std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
        " 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty double z\n"
        "element face 2\nproperty uchar flags\nproperty list uchar uint vertex_indices\n"
        "end_header\n";
    const double points[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}};
    for (const auto& p : points)
      for (const double v : p) append(header, v, big_endian);
    const std::vector<std::vector<std::uint32_t>> faces = {{0, 1, 2, 3}, {1, 4, 2}};
    for (const auto& face : faces) {
      header += '\x07';
      header += static_cast<char>(face.size());
      for (const std::uint32_t i : face) append(header, i, big_endian);
    }
    return header;
  }

  template <typename T>
  static void append(std::string& out, T value, bool big_endian) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (big_endian) std::reverse(bytes, bytes + sizeof(T));
    out.append(bytes, sizeof(T));
  }
};

TEST_F(PlyFileTest, AsciiQuadsAndTrianglesWithNormalsAndOtherElementsSkipped) {
  write("quad.ply", ascii_quad);
  const Model model = load("quad.ply");
  ASSERT_EQ(model.parts.size(), 1u);
  const Mesh& mesh = model.parts[0].mesh;
  EXPECT_EQ(mesh.triangles.size(), 3u);
  EXPECT_EQ(mesh.positions.size(), 5u);
  ASSERT_EQ(mesh.normals.size(), 5u);
  EXPECT_EQ(mesh.normals[4], Vec3(0, 0, 1));
}

TEST_F(PlyFileTest, BinaryOfEitherByteOrderReadsAsTheAsciiDoes) {
  write("quad.ply", ascii_quad);
  write("little.ply", binary(false));
  write("big.ply", binary(true));
  const Mesh ascii = load("quad.ply", NormalsMode::flat).parts[0].mesh;
  for (const char* name : {"little.ply", "big.ply"}) {
    const Mesh mesh = load(name).parts[0].mesh;
    EXPECT_EQ(mesh.positions, ascii.positions) << name;
    EXPECT_EQ(mesh.triangles, ascii.triangles) << name;
    EXPECT_TRUE(mesh.normals.empty()) << name;
  }
}

TEST_F(PlyFileTest, ErrorsNameTheLineOrTheByte) {
  std::string text(ascii_quad);
  text.replace(text.find("3 1 4 2"), 7, "3 1 5 2");
  write("index.ply", text);
  EXPECT_EQ(load_error("index.ply"),
            "index.ply:line 23: vertex index 5 must be below the 5 vertices");
  std::string bad_number(ascii_quad);
  bad_number.replace(bad_number.find("1 1 0 0 0 1"), 11, "1 one 0 0 0 1");
  write("number.ply", bad_number);
  EXPECT_EQ(load_error("number.ply"), "number.ply:line 19: \"one\" is not a finite number");

  const std::string whole = binary(false);
  write("truncated.ply", whole.substr(0, whole.size() - 2));
  EXPECT_THAT(load_error("truncated.ply"), HasSubstr("truncated.ply:byte "));
  write("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
  EXPECT_THAT(load_error("noend.ply"), HasSubstr("the header has no end_header"));
  write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n");
  EXPECT_EQ(load_error("type.ply"), "type.ply:line 4: unknown property type \"quad\"");
  write("notply.ply", "solid cube\n");
  EXPECT_THAT(load_error("notply.ply"), HasSubstr("a PLY file starts with \"ply\""));
}

// Float vertices and faces of a uchar count and uint indices: the layout that little-endian
// files are read from straight, big-endian ones value by value. Two triangles, a quad, then
// a triangle, so that the straight read hands over to the general one midway.
std::string float_grid(bool big_endian, std::uint32_t last_index = 4, float last_x = 2) {
  std::string out = std::string("ply\nformat ") +
                    (big_endian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                    "property float u\nproperty float v\nelement face 4\n"
                    "property list uchar uint vertex_indices\nend_header\n";
  const auto put = [&](auto value) {
    char bytes[sizeof(value)];
    std::memcpy(bytes, &value, sizeof(value));
    if (big_endian) std::reverse(bytes, bytes + sizeof(value));
    out.append(bytes, sizeof(value));
  };
  const float points[6][5] = {{0, 0, 0, 0, 0}, {1, 0, 0, 1, 0},      {1, 1, 0, 1, 1},
                              {0, 1, 0, 0, 1}, {last_x, 0, 0, 2, 0}, {2, 1, 0, 2, 1}};
  for (const auto& p : points)
    for (const float v : p) put(v);
  const std::vector<std::vector<std::uint32_t>> faces = {
      {0, 1, 2}, {0, 2, 3}, {1, 4, 5, 2}, {1, 5, last_index}};
  for (const auto& face : faces) {
    out += static_cast<char>(face.size());
    for (const std::uint32_t i : face) put(i);
  }
  return out;
}

TEST_F(PlyFileTest, LittleEndianFloatsAndTrianglesReadStraightAsTheGeneralPathReadsThem) {
  write("little.ply", float_grid(false));
  write("big.ply", float_grid(true));
  const Mesh little = load("little.ply").parts[0].mesh;
  const Mesh big = load("big.ply").parts[0].mesh;
  EXPECT_EQ(little.positions, big.positions);
  EXPECT_EQ(little.triangles, big.triangles);
  EXPECT_EQ(little.uvs, big.uvs);
  EXPECT_EQ(little.triangles.size(), 5u);
  ASSERT_EQ(little.uvs.size(), little.positions.size());
  // The straight read stops at a bad value, and the general path names its byte: after the
  // 204 bytes of the header, the fifth vertex's x at 4 x 20 bytes into the vertices; the
  // fourth face's third index after the 120 bytes of vertices and 13 + 13 + 17 + 9 of faces.
  write("index.ply", float_grid(false, 6));
  EXPECT_EQ(load_error("index.ply"),
            "index.ply:byte 376: vertex index 6 must be below the 6 vertices");
  write("nan.ply", float_grid(false, 4, std::numeric_limits<float>::quiet_NaN()));
  EXPECT_EQ(load_error("nan.ply"), "nan.ply:byte 284: holds a value that is not a finite number");
}

TEST_F(PlyFileTest, HugeCountsAreRefusedFromTheHeader) {
  write("huge.ply",
        "ply\nformat binary_little_endian 1.0\nelement vertex 2147483648\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n0123456789ab");
  EXPECT_THAT(load_error("huge.ply"),
              HasSubstr("huge.ply:line 3: claims 2147483648 vertex elements, more than the "
                        "file's 12 bytes"));
  write("faces.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 2147483648\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  try {
    load("faces.ply", NormalsMode::file, 100);
    FAIL() << "a header of 2^31 faces was read";
  } catch (const SceneFileError& e) {
    EXPECT_EQ(e.limit(), "max_triangles");
    EXPECT_THAT(e.what(), HasSubstr("faces.ply:line 7: needs at least 2147483648 triangles"));
  }
}

}  // namespace
}  // namespace tessera
