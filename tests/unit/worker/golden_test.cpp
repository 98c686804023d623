// The examples, rendered small, against reference images in tests/golden/.
// Regenerate after an intended change of the images with:
//   TESSERA_UPDATE_GOLDEN=1 build/tests/tessera_tests --gtest_filter='Golden*'
// then look at the new files before committing them.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>

#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "common/mesh_files/folder_scene_files.hpp"
#include "common/scn/scn_import.hpp"
#include "tests/unit/worker/render_helpers.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;

constexpr int kGoldenWidth = 160;
// Identical builds give identical bits; the tolerance leaves room for a different libm or
// Embree version breaking a tie between two surfaces at one pixel.
constexpr float kPixelTolerance = 1e-3f;
constexpr double kMaxMismatchFraction = 0.002;

struct Example {
  std::string name;
  fs::path path;
};

std::vector<Example> examples() {
  std::vector<Example> list;
  for (const auto& entry : fs::directory_iterator(fs::path(TESSERA_SOURCE_DIR) / "examples"))
    if (entry.path().extension() == ".json")
      list.push_back({entry.path().stem().string(), entry.path()});
  list.push_back({"mesh", fs::path(TESSERA_BINARY_DIR) / "examples" / "mesh.json"});
  list.push_back(
      {"gltf_carousel", fs::path(TESSERA_BINARY_DIR) / "examples" / "gltf_carousel.json"});
  list.push_back(
      {"textured_globe", fs::path(TESSERA_BINARY_DIR) / "examples" / "textured_globe.json"});
  list.push_back(
      {"course_temple", fs::path(TESSERA_SOURCE_DIR) / "examples" / "course" / "temple.scn"});
  std::sort(list.begin(), list.end(), [](auto& a, auto& b) { return a.name < b.name; });
  return list;
}

// An example's scene: JSON, or a COS 426 .scn converted as `tessera render` converts it.
nlohmann::json read_example(const fs::path& path) {
  return path.extension() == ".scn" ? import_scn(path) : read_json_file(path);
}

void PrintTo(const Example& example, std::ostream* out) { *out << example.name; }

class GoldenTest : public ::testing::TestWithParam<Example> {};

// `image` against tests/golden/NAME.exr, or written there with TESSERA_UPDATE_GOLDEN=1.
void expect_matches_golden(const Image& image, const std::string& name) {
  // What a worker uploads must be what the coordinator accepts: finite values of 0 or more.
  const auto pixels = image.pixels();
  const auto impossible = std::find_if(pixels.begin(), pixels.end(),
                                       [](float v) { return !(v >= 0.0f && std::isfinite(v)); });
  EXPECT_EQ(impossible, pixels.end()) << "value " << (impossible - pixels.begin()) << " is "
                                      << (impossible == pixels.end() ? 0.0f : *impossible);

  const fs::path golden = fs::path(TESSERA_SOURCE_DIR) / "tests" / "golden" / (name + ".exr");
  if (const char* update = std::getenv("TESSERA_UPDATE_GOLDEN"); update && *update == '1') {
    fs::create_directories(golden.parent_path());
    write_image(image, golden, OutputTransfer::linear);
    GTEST_SKIP() << "wrote " << golden;
  }
  ASSERT_TRUE(fs::exists(golden)) << golden << " is missing; see the top of " << __FILE__;
  const Image reference = read_image(golden);
  ASSERT_EQ(reference.width(), image.width());
  ASSERT_EQ(reference.height(), image.height());
  std::size_t mismatched = 0;
  double max_difference = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      float worst = 0;
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::fabs(image.pixel(x, y)[c] - reference.pixel(x, y)[c]));
      mismatched += worst > kPixelTolerance;
      max_difference = std::max<double>(max_difference, worst);
    }
  const double fraction =
      static_cast<double>(mismatched) / (static_cast<double>(image.width()) * image.height());
  EXPECT_LE(fraction, kMaxMismatchFraction)
      << mismatched << " pixels differ by more than " << kPixelTolerance << " (largest difference "
      << max_difference << ")";
}

// The document at the golden images' size.
void shrink(nlohmann::json& document) {
  const int width = document["image"]["width"];
  const int height = document["image"]["height"];
  document["image"]["width"] = kGoldenWidth;
  document["image"]["height"] = std::max(1, kGoldenWidth * height / width);
}

TEST_P(GoldenTest, MatchesReferenceImage) {
  nlohmann::json document = read_example(GetParam().path);
  shrink(document);
  const FolderSceneFiles files(GetParam().path.parent_path());
  expect_matches_golden(test::render_image(document, 2, 0, &files), GetParam().name);
}

INSTANTIATE_TEST_SUITE_P(Examples, GoldenTest, ::testing::ValuesIn(examples()),
                         [](const auto& info) { return info.param.name; });

TEST(ExamplesTest, CoverEveryFeature) {
  std::set<std::string> lights, shapes;
  bool checker = false, transmissive = false, deep = false, big_mesh = false;
  for (const Example& example : examples()) {
    const FolderSceneFiles files(example.path.parent_path());
    const Scene scene = parse_scene(read_example(example.path), Limits{}, nullptr, &files);
    for (const Light& light : scene.lights) lights.insert(std::to_string(light.index()));
    for (const Object& object : scene.objects) {
      shapes.insert(std::to_string(object.shape.index()));
      if (const auto* mesh = std::get_if<Mesh>(&object.shape))
        big_mesh |= mesh->triangles.size() >= 100000;
    }
    for (const Material& material : scene.materials) {
      checker |= material.checker.has_value();
      transmissive |= material.transmission != Color(0.0);
    }
    deep |= scene.render.max_depth >= 12;
  }
  EXPECT_EQ(lights.size(), 3u);
  EXPECT_EQ(shapes.size(), 7u);
  EXPECT_TRUE(checker);
  EXPECT_TRUE(transmissive);
  EXPECT_TRUE(deep);
  EXPECT_TRUE(big_mesh);
}

// Frames of the animations in examples/animation/, each against its own image.
struct AnimationFrame {
  std::string name;
  int frame;
};

void PrintTo(const AnimationFrame& shown, std::ostream* out) {
  *out << shown.name << " frame " << shown.frame;
}

class GoldenFramesTest : public ::testing::TestWithParam<AnimationFrame> {};

TEST_P(GoldenFramesTest, MatchReferenceImages) {
  const fs::path path =
      fs::path(TESSERA_SOURCE_DIR) / "examples" / "animation" / (GetParam().name + ".json");
  nlohmann::json document = read_json_file(path);
  shrink(document);
  const Renderer renderer(parse_scene_frame(document, GetParam().frame, Limits{}));
  expect_matches_golden(render_local(renderer, 2).image,
                        GetParam().name + "_" + std::to_string(GetParam().frame));
}

INSTANTIATE_TEST_SUITE_P(
    Animations, GoldenFramesTest,
    ::testing::Values(AnimationFrame{"turntable", 1}, AnimationFrame{"turntable", 13},
                      AnimationFrame{"turntable", 30}, AnimationFrame{"corridor_flythrough", 1},
                      AnimationFrame{"corridor_flythrough", 30},
                      AnimationFrame{"corridor_flythrough", 60}),
    [](const auto& info) { return info.param.name + "_" + std::to_string(info.param.frame); });

}  // namespace
}  // namespace tessera
