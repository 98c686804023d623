// tessera import: every mistake in a .scn file is one message naming the file and line.
#include <string>

#include <gtest/gtest.h>

#include "tests/unit/common/scn_test_support.hpp"

namespace tessera::scn_test {
namespace {

class ScnErrorTest : public ScnImportTest {
 protected:
  // The error for a scene.scn of `text`, whose line `line` is at fault.
  ::testing::AssertionResult fails(const std::string& text, std::size_t line,
                                   const std::string& detail,
                                   const ScnImportOptions& options = {}) {
    write("scene.scn", text);
    const std::string error = error_of("scene.scn", options);
    if (error == at("scene.scn", line) + detail) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "got: " << error;
  }
};

TEST_F(ScnErrorTest, WrongNumberOfValues) {
  EXPECT_TRUE(fails(camera + "sphere 0 1 2 3\n", 2,
                    "sphere needs 5 numbers (material, x, y, z, radius), got 4"));
  EXPECT_TRUE(fails(camera + "\n\nbox -1 0 0 0 1 1 1 1\n", 4,
                    "box needs 7 numbers (material, low x, y, z, high x, y, z), got 8"));
  EXPECT_TRUE(fails(camera + "end 3\n", 2, "end needs no values, got 1"));
  EXPECT_TRUE(fails("camera 0 0 5 0 0 -1 0 1 0 0.5 0.01\n", 1,
                    "camera needs 12 numbers (eye x, y, z, towards x, y, z, up x, y, z, xfov, "
                    "neardist, fardist), got 11"));
}

TEST_F(ScnErrorTest, UnknownKeywordsAreNamedWhereTheyAre) {
  EXPECT_TRUE(
      fails(camera + "spher 0 0 0 0 1\n", 2, "unknown keyword 'spher'; did you mean 'sphere'?"));
  // A short command runs into a misspelt one: the misspelling is the mistake.
  EXPECT_TRUE(fails(camera + "sphere 0 0 0 0\nsphree 0 0 0 0 1\n", 3,
                    "unknown keyword 'sphree'; did you mean 'sphere'?"));
  EXPECT_TRUE(fails(camera + "area_light 1 1 1 0 0 0 0 -1 0 1 1 0 0\n", 2,
                    "'area_light' is a COS 426 command tessera does not import"));
}

TEST_F(ScnErrorTest, ValuesThatAreNotNumbers) {
  EXPECT_TRUE(
      fails(camera + "sphere -1\n 0 0 0\n abc\n", 4, "sphere radius must be a number, got 'abc'"));
  EXPECT_TRUE(fails(camera + "ambient 0.1 nan 0.1\n", 2, "ambient g must be a number, got 'nan'"));
  EXPECT_TRUE(
      fails(camera + "background 1e999 0 0\n", 2, "background r must be a number, got '1e999'"));
}

TEST_F(ScnErrorTest, MaterialIndices) {
  const std::string material = "material 0 0 0 1 1 1 0 0 0 0 0 0 0 0 0 1 1 0\n";
  EXPECT_TRUE(fails(camera + material + "sphere 1 0 0 0 1\n", 3,
                    "material 1 is not defined: this file defines 1 before this line (0 to 0)"));
  EXPECT_TRUE(fails(camera + "sphere 0 0 0 0 1\n" + material, 2,
                    "material 0 is not defined: this file defines none before this line"));
  EXPECT_TRUE(fails(camera + "sphere -2 0 0 0 1\n", 2,
                    "sphere material must be -1 or the index of a material, got '-2'"));
  EXPECT_TRUE(fails(camera + "sphere 0.5 0 0 0 1\n", 2,
                    "sphere material must be -1 or the index of a material, got '0.5'"));
  EXPECT_TRUE(fails(camera + "material 0 0 0 1 1 1 0 0 0 0 0 0 0 0 0 1 1 wood.ppm\n", 2,
                    "material texture 'wood.ppm': tessera has no textures; write 0 for none"));
}

TEST_F(ScnErrorTest, BeginAndEnd) {
  EXPECT_TRUE(fails(camera + "begin -1 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\nsphere -1 0 0 0 1\n", 2,
                    "begin has no matching end before the end of the file"));
  EXPECT_TRUE(fails(camera + "end\n", 2, "end without a begin"));
  EXPECT_TRUE(fails(camera + "begin -1\n 1 0 0 0\n 0 1 0 0\n 0 0 1 0\n 0 0 1 1\nend\n", 6,
                    "begin's matrix must be affine: its last row must be 0 0 0 1, got 0 0 1 1"));
  EXPECT_TRUE(fails(camera + "begin -1 1 0 0 0 0 0 0 0 0 0 1 0 0 0 0 1\nend\n", 2,
                    "begin's matrix must be invertible, but its 3x3 part has determinant 0"));
  // Each block alone is fine; together they flatten space.
  const std::string shrink = "begin -1 1e-7 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n";
  write("scene.scn", camera + shrink + shrink + "end\nend\n");
  const std::string error = error_of("scene.scn");
  EXPECT_EQ(error.rfind(at("scene.scn", 3) +
                            "begin's matrix with those of the enclosing blocks flattens space or "
                            "overflows (determinant of the combined 3x3 part 9.99",
                        0),
            0u)
      << error;
}

TEST_F(ScnErrorTest, Includes) {
  EXPECT_TRUE(fails(camera + "include missing.scn\n", 2,
                    "cannot read included file " + (dir_ / "missing.scn").string() +
                        ": No such file or directory"));
  write("a.scn", "include b.scn\n");
  write("b.scn", "\ninclude a.scn\n");
  const std::string a = (dir_ / "a.scn").string();
  const std::string b = (dir_ / "b.scn").string();
  write("scene.scn", camera + "include a.scn\n");
  // Reported where the cycle closes, in b.scn.
  EXPECT_EQ(error_of("scene.scn"), at("b.scn", 2) +
                                       "include cycle: " + (dir_ / "scene.scn").string() + " -> " +
                                       a + " -> " + b + " -> " + a);
}

TEST_F(ScnErrorTest, IncludesNestAtMostSixteenDeep) {
  for (int i = 1; i < 16; ++i)
    write("n" + std::to_string(i) + ".scn", "include n" + std::to_string(i + 1) + ".scn\n");
  write("n16.scn", "sphere -1 0 0 0 1\n");
  write("top.scn", camera + "include n1.scn\n");
  EXPECT_EQ(error_of("top.scn"), "");  // n16 is 16 includes deep
  write("n16.scn", "include n17.scn\n");
  write("n17.scn", "sphere -1 0 0 0 1\n");
  const std::string error = error_of("top.scn");
  EXPECT_EQ(error.rfind(at("n16.scn", 1) + "includes nest more than 16 deep: ", 0), 0u) << error;
}

TEST_F(ScnErrorTest, ValuesOurFormatCannotHold) {
  EXPECT_TRUE(
      fails(camera + "spot_light 1 1 1 0 5 0 0 -1 0 1 0 0 2 1\n", 2,
            "spot_light sc (the cone's half-angle, in radians) must be in (0, pi/2], got 2"));
  EXPECT_TRUE(fails(camera + "point_light 1 1 1 0 5 0 0 0 0\n", 2,
                    "point_light ca, la and qa must not all be 0 (infinitely bright)"));
  EXPECT_TRUE(
      fails(camera + "dir_light 1 1 1 0 0 0\n", 2, "dir_light direction must not be 0 0 0"));
  EXPECT_TRUE(fails(camera + "sphere -1 0 0 0 -1\n", 2, "sphere radius must be > 0, got -1"));
  EXPECT_TRUE(fails(camera + "box -1 0 0 0 1 -1 1\n", 2,
                    "box high corner must be greater than the low one in x, y and z"));
  EXPECT_TRUE(fails(camera + "tri -1 0 0 0 1 1 1 2 2 2\n", 2,
                    "tri is degenerate: its corners coincide or lie on one line"));
  EXPECT_TRUE(fails(camera + "material 0 0 0 -1 1 1 0 0 0 0 0 0 0 0 0 1 1 0\n", 2,
                    "material kd r must be >= 0, got -1"));
  EXPECT_TRUE(fails("camera 0 0 5 0 0 -1 0 0 1 0.5 0.01 100\n", 1,
                    "camera up must not be parallel to towards"));
  EXPECT_TRUE(fails("camera 0 0 5 0 0 -1 0 1 0 1.6 0.01 100\n", 1,
                    "camera xfov (half the horizontal angle, in radians) must be in (0, pi/2), "
                    "got 1.6"));
  EXPECT_TRUE(fails(
      camera + "mesh -1 nowhere.off\n", 2,
      "mesh file 'nowhere.off' not found (looked for " + (dir_ / "nowhere.off").string() + ")"));
}

TEST_F(ScnErrorTest, NoCamera) {
  write("scene.scn", "sphere -1 0 0 0 1\n");
  EXPECT_EQ(error_of("scene.scn"),
            (dir_ / "scene.scn").string() +
                ": has no camera command; tessera needs one (the course's reader made one up "
                "from the scene's bounding box)");
}

TEST_F(ScnErrorTest, CountsAndSizesAreBounded) {
  ScnImportOptions small;
  small.limits.max_objects = 2;
  small.limits.max_lights = 1;
  small.limits.max_materials = 1;
  EXPECT_TRUE(fails(camera + "sphere -1 0 0 0 1\nsphere -1 0 0 0 1\nsphere -1 0 0 0 1\n", 4,
                    "more than 2 objects (limit max_objects)", small));
  EXPECT_TRUE(fails(camera + "dir_light 1 1 1 0 -1 0\ndir_light 1 1 1 0 -1 0\n", 3,
                    "more than 1 lights (limit max_lights)", small));
  const std::string material = "material 0 0 0 1 1 1 0 0 0 0 0 0 0 0 0 1 1 0\n";
  EXPECT_TRUE(
      fails(camera + material + material, 3, "more than 1 materials (limit max_materials)", small));
  small.limits.max_triangles = 20;
  EXPECT_TRUE(fails(camera + "box -1 0 0 0 1 1 1\nbox -1 0 0 0 1 1 1\n", 3,
                    "more than 20 triangles in boxes and triangles (limit max_triangles)", small));

  ScnImportOptions tiny;
  tiny.max_file_bytes = 100;
  write("scene.scn", camera + std::string(100, ' '));
  EXPECT_EQ(error_of("scene.scn", tiny),
            (dir_ / "scene.scn").string() + ": cannot read: is larger than 100 bytes");
  tiny.max_file_bytes = 1000;
  tiny.max_total_bytes = 120;
  write("part.scn", "sphere -1 0 0 0 1" + std::string(60, ' '));
  write("scene.scn", camera + "include part.scn\n");
  EXPECT_EQ(error_of("scene.scn", tiny), at("scene.scn", 2) + "cannot read included file " +
                                             (dir_ / "part.scn").string() +
                                             ": the files read so far are over 120 bytes in all");
}

TEST_F(ScnErrorTest, ImageSizeOutsideTheLimits) {
  write("scene.scn", camera);
  ScnImportOptions wide;
  wide.width = 20000;
  EXPECT_THROW(import("scene.scn", wide), std::invalid_argument);
}

}  // namespace
}  // namespace tessera::scn_test
