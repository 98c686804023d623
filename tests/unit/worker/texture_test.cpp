// Image textures: known answers (a magnified texture gives the bilinear blend of its texels,
// a minified one the mean of its mip level), sRGB decoding, the footprint through a mirror,
// each shape's uv convention, and the same bits for any tiling, thread count or packet.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>

#include "common/image/image_io.hpp"
#include "common/mesh_files/folder_scene_files.hpp"
#include "tests/png_header_only.hpp"
#include "tests/unit/worker/render_helpers.hpp"

namespace tessera {
namespace {

using test::json;
using ::testing::HasSubstr;

class TextureTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("tessera-texture-" + std::to_string(::getpid()) + "-" + info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A texture of `width` x `height` texels whose texel (x, y) (y down the image) has the
  // linear value `value(x, y)` in every channel.
  template <typename Value>
  void write_texture(const std::string& name, int width, int height, Value value,
                     OutputTransfer transfer = OutputTransfer::linear) {
    Image image(width, height);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        float* p = image.pixel(x, y);
        const float v = value(x, y);
        p[0] = v;
        p[1] = v * 0.5f;
        p[2] = 1.0f - v;
      }
    write_image(image, dir_ / name, transfer);
  }

  Renderer renderer(const json& scene) const {
    const FolderSceneFiles files(dir_);
    return Renderer(parse_scene(scene, Limits{}, nullptr, &files));
  }

  Image render(const json& scene, int threads = 1, int tile_size = 0) const {
    const FolderSceneFiles files(dir_);
    return test::render_image(scene, threads, tile_size, &files);
  }

  std::filesystem::path dir_;
};

// A square image looking straight at the plane z = 0 from (cx, cy, distance).
json facing_plane(double cx, double cy, double distance, int pixels, double fov) {
  json scene = test::pinhole_scene({cx, cy, distance}, {cx, cy, 0});
  scene["image"] = {{"width", pixels}, {"height", pixels}};
  scene["camera"]["fov_y"] = fov;
  return scene;
}

json emitting(const json& texture) {
  return {{"ambient", 0}, {"diffuse", 0}, {"specular", 0}, {"emission", texture}};
}

json plane_z(const json& material) {
  return {{"type", "plane"}, {"point", {0, 0, 0}}, {"normal", {0, 0, 1}}, {"material", material}};
}

// Where pixel (x, y)'s ray meets z = 0.
glm::dvec2 on_plane(const Renderer& renderer, int x, int y) {
  const Ray ray = renderer.camera().ray_through(x + 0.5, y + 0.5);
  const double t = -static_cast<double>(ray.origin.z) / ray.direction.z;
  return {ray.origin.x + t * ray.direction.x, ray.origin.y + t * ray.direction.y};
}

float texel_value(int x, int y) {
  return 0.1f + 0.2f * static_cast<float>(x) + 0.05f * static_cast<float>(y);
}

TEST_F(TextureTest, AMagnifiedTextureGivesTheBilinearBlendOfItsTexels) {
  write_texture("grid.exr", 4, 4, texel_value);
  // The unit square fills the view; each texel spans about 16 pixels.
  json scene = facing_plane(0.5, 0.5, 1.0, 64, 53.13010235415598);
  scene["objects"].push_back(plane_z(emitting({{"texture", "grid.exr"}, {"wrap", "clamp"}})));
  const Renderer r = renderer(scene);
  const Image image = render_local(r, 1, 0).image;
  int checked = 0;
  for (int y = 3; y < 64; y += 7)
    for (int x = 2; x < 64; x += 5) {
      const glm::dvec2 uv = on_plane(r, x, y);
      // s = u, t = 1 - v; texel centres at (i + 0.5) / 4.
      const double fx = std::clamp(uv.x * 4 - 0.5, 0.0, 3.0);
      const double fy = std::clamp((1 - uv.y) * 4 - 0.5, 0.0, 3.0);
      const int x0 = std::min(static_cast<int>(fx), 2);
      const int y0 = std::min(static_cast<int>(fy), 2);
      const double ax = fx - x0;
      const double ay = fy - y0;
      const double expected =
          (1 - ay) * ((1 - ax) * texel_value(x0, y0) + ax * texel_value(x0 + 1, y0)) +
          ay * ((1 - ax) * texel_value(x0, y0 + 1) + ax * texel_value(x0 + 1, y0 + 1));
      const float* p = image.pixel(x, y);
      EXPECT_NEAR(p[0], expected, 2e-5) << "pixel " << x << ", " << y;
      EXPECT_NEAR(p[1], expected * 0.5, 2e-5) << "pixel " << x << ", " << y;
      EXPECT_NEAR(p[2], 1.0 - expected, 2e-5) << "pixel " << x << ", " << y;
      ++checked;
    }
  EXPECT_GT(checked, 100);
}

// Texels alternating 0 and 1: seen from far off, each pixel covers many of them, and the
// mip-map gives their mean where a lookup of one texel would give 0 or 1.
float checker(int x, int y) { return static_cast<float>((x + y) % 2); }

TEST_F(TextureTest, AMinifiedTextureGivesTheMeanOfTheTexelsUnderThePixel) {
  write_texture("fine.exr", 256, 256, checker);
  // 256 texels over 8 pixels: 32 texels a pixel.
  json scene = facing_plane(0.5, 0.5, 1.0, 8, 53.13010235415598);
  scene["objects"].push_back(plane_z(emitting({{"texture", "fine.exr"}})));
  const Image image = render(scene);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_NEAR(image.pixel(x, y)[0], 0.5, 0.02) << x << ", " << y;
}

TEST_F(TextureTest, ThePixelConeWidensThroughAMirror) {
  // The same far texture, seen only in a mirror: the path's whole length sizes the
  // footprint, so the reflection is filtered to grey too.
  write_texture("fine.exr", 256, 256, checker);
  json scene = test::pinhole_scene({0.5, 0.5, 0.5}, {0.5, 0.5, 1.0});
  scene["image"] = {{"width", 8}, {"height", 8}};
  scene["camera"]["fov_y"] = 53.13010235415598;
  scene["objects"].push_back(plane_z(emitting({{"texture", "fine.exr"}})));
  scene["objects"].push_back({{"type", "plane"},
                              {"point", {0, 0, 1.0}},
                              {"normal", {0, 0, -1}},
                              {"material", {{"ambient", 0}, {"diffuse", 0}, {"reflection", 1}}}});
  const Image image = render(scene);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_NEAR(image.pixel(x, y)[0], 0.5, 0.03) << x << ", " << y;
}

TEST_F(TextureTest, EightBitImagesAreDecodedFromSrgb) {
  // Written as sRGB (as PNGs are), read back linear: 0.2 comes back as 0.2, not the 0.48
  // its sRGB code would read as.
  write_texture(
      "flat.png", 2, 2, [](int, int) { return 0.2f; }, OutputTransfer::srgb);
  json scene = facing_plane(0.5, 0.5, 1.0, 4, 40);
  scene["objects"].push_back(plane_z(emitting({{"texture", "flat.png"}})));
  const Image image = render(scene);
  EXPECT_NEAR(image.pixel(1, 1)[0], 0.2, 0.003);
  EXPECT_NEAR(image.pixel(1, 1)[2], 0.8, 0.006);
}

TEST_F(TextureTest, ScaleMultipliesAndWrapRepeatsClampsOrMirrors) {
  // A 2x1 texture, 0.25 then 0.75 left to right, over u from -1 to 2.
  write_texture("two.exr", 2, 1, [](int x, int) { return x == 0 ? 0.25f : 0.75f; });
  const auto value_at = [&](const std::string& wrap, double u) {
    json scene = facing_plane(u, 0.5, 1.0, 1, 1);
    scene["objects"].push_back(
        plane_z(emitting({{"texture", "two.exr"}, {"scale", 2}, {"wrap", wrap}})));
    return render(scene).pixel(0, 0)[0];
  };
  EXPECT_NEAR(value_at("repeat", 1.25), 2 * 0.25, 1e-3);
  EXPECT_NEAR(value_at("repeat", -0.25), 2 * 0.75, 1e-3);
  EXPECT_NEAR(value_at("clamp", 1.6), 2 * 0.75, 1e-3);
  EXPECT_NEAR(value_at("clamp", -0.6), 2 * 0.25, 1e-3);
  EXPECT_NEAR(value_at("mirror", 1.25), 2 * 0.75, 1e-3);
  EXPECT_NEAR(value_at("mirror", -0.25), 2 * 0.25, 1e-3);
}

TEST_F(TextureTest, DiffuseAndAmbientTexturesShadeAsTheirColours) {
  write_texture("flat.exr", 2, 2, [](int, int) { return 0.5f; });
  json scene = facing_plane(0.5, 0.5, 1.0, 1, 10);
  scene["ambient_light"] = 0.2;
  scene["lights"].push_back({{"type", "directional"}, {"direction", {0, 0, -1}}, {"intensity", 1}});
  scene["objects"].push_back(plane_z({{"ambient", {{"texture", "flat.exr"}}},
                                      {"diffuse", {{"texture", "flat.exr"}, {"scale", 0.5}}},
                                      {"specular", 0}}));
  const Image image = render(scene);
  const float* p = image.pixel(0, 0);
  // K_A·I_A + K_D·(N·L)·I_L, channel by channel.
  EXPECT_NEAR(p[0], 0.5 * 0.2 + 0.25 * 1.0, 1e-4);
  EXPECT_NEAR(p[1], 0.25 * 0.2 + 0.125 * 1.0, 1e-4);
  EXPECT_NEAR(p[2], 0.5 * 0.2 + 0.25 * 1.0, 1e-4);
}

// The texel a shape shows at a hit: a texture with one value per quarter (u < 0.5 or not,
// v < 0.5 or not) tells which quarter of texture space the hit fell in.
float quarter(int x, int y) { return (x < 32 ? 0.0f : 0.5f) + (y < 32 ? 0.25f : 0.0f); }

TEST_F(TextureTest, ShapesFollowTheirUvConventions) {
  write_texture("quarters.exr", 64, 64, quarter);
  // Each returns the emitted red at a ray straight down -z (or as given) onto the shape.
  const auto seen = [&](const json& shape, Vec3 eye, Vec3 at) {
    json scene =
        test::pinhole_scene(eye, at, std::fabs(eye.y - at.y) > 0 ? Vec3(0, 0, -1) : Vec3(0, 1, 0));
    scene["camera"]["fov_y"] = 0.1;  // a footprint far smaller than a quarter
    json object = shape;
    object["material"] = emitting({{"texture", "quarters.exr"}, {"wrap", "clamp"}});
    scene["objects"].push_back(object);
    return render(scene).pixel(0, 0)[0];
  };
  // quarter(): u >= 0.5 adds 0.5, v >= 0.5 (the image's top half) adds 0.25.
  const json sphere = {{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}};
  EXPECT_NEAR(seen(sphere, {0.3, 0.3, 5}, {0.3, 0.3, 0}), 0.75, 1e-3);     // u, v > 0.5
  EXPECT_NEAR(seen(sphere, {-0.3, -0.3, 5}, {-0.3, -0.3, 0}), 0.0, 1e-3);  // u, v < 0.5
  const json box = {{"type", "box"}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}};
  EXPECT_NEAR(seen(box, {0.8, 0.2, 5}, {0.8, 0.2, 0}), 0.5, 1e-3);    // +z face: u = x, v = y
  EXPECT_NEAR(seen(box, {0.8, 5, 0.2}, {0.8, 0, 0.2}), 0.75, 1e-3);   // +y face: v = 1 - z
  EXPECT_NEAR(seen(box, {-5, 0.8, 0.8}, {0, 0.8, 0.8}), 0.75, 1e-3);  // -x face: u = z
  const json triangle = {{"type", "triangle"},
                         {"vertices", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}},
                         {"uvs", {{0, 1}, {1, 1}, {0, 0}}}};
  // Near (0, 0): uv (0, 1), the top left quarter.
  EXPECT_NEAR(seen(triangle, {0.1, 0.1, 5}, {0.1, 0.1, 0}), 0.25, 1e-3);
  const json floor = {
      {"type", "plane"}, {"point", {0, 0, 0}}, {"normal", {0, 1, 0}}, {"uv_scale", 2}};
  // On a floor u = x / 2 and v = -z / 2.
  EXPECT_NEAR(seen(floor, {1.6, 5, -1.4}, {1.6, 0, -1.4}), 0.75, 1e-3);
  EXPECT_NEAR(seen(floor, {0.4, 5, 0.6}, {0.4, 0, 0.6}), 0.0, 1e-3);
  const json cylinder = {{"type", "cylinder"}, {"center", {0, 0, 0}}, {"radius", 1}, {"height", 2}};
  EXPECT_NEAR(seen(cylinder, {0.3, 0.5, 5}, {0.3, 0.5, 0}), 0.75, 1e-3);
}

TEST_F(TextureTest, TexturedPixelsHaveTheSameBitsForAnyTilingThreadsAndPackets) {
  write_texture("grid.exr", 64, 32,
                [](int x, int y) { return std::fmod(0.37f * x + 0.11f * y, 1.0f); });
  json scene = test::pinhole_scene({0, 1.5, 5}, {0, 0.5, 0});
  scene["image"] = {{"width", 37}, {"height", 29}};
  scene["camera"]["fov_y"] = 50;
  scene["ambient_light"] = 0.1;
  scene["lights"].push_back({{"type", "point"}, {"position", {2, 4, 3}}, {"intensity", 1}});
  const json textured = {
      {"diffuse", {{"texture", "grid.exr"}}}, {"specular", 0.3}, {"shininess", 20}};
  scene["objects"].push_back(
      {{"type", "sphere"}, {"center", {0, 1, 0}}, {"radius", 1}, {"material", textured}});
  scene["objects"].push_back(
      {{"type", "plane"},
       {"point", {0, 0, 0}},
       {"normal", {0, 1, 0}},
       {"material",
        {{"diffuse", {{"texture", "grid.exr"}, {"wrap", "mirror"}}}, {"reflection", 0.3}}}});
  const Image reference = render(scene, 1, 0);
  for (const auto& [threads, tile] : {std::pair{2, 5}, std::pair{2, 16}, std::pair{1, 64}}) {
    const Image other = render(scene, threads, tile);
    ASSERT_EQ(other.pixels().size(), reference.pixels().size());
    EXPECT_TRUE(
        std::equal(other.pixels().begin(), other.pixels().end(), reference.pixels().begin()))
        << threads << " threads, tiles of " << tile;
  }
  // One ray at a time, as trace() takes it, against the packets render_tile() sends.
  const Renderer r = renderer(scene);
  for (int y = 0; y < 29; y += 3)
    for (int x = 0; x < 37; x += 4) {
      RayCounts counts;
      const Color single = r.tracer().trace(r.camera().ray_through(x + 0.5, y + 0.5), 0, counts);
      const float* p = reference.pixel(x, y);
      EXPECT_EQ(static_cast<float>(single.r), p[0]) << x << ", " << y;
      EXPECT_EQ(static_cast<float>(single.b), p[2]) << x << ", " << y;
    }
}

using test::png_header_only;

TEST_F(TextureTest, TexturesOverThePixelLimitsAreRefusedBeforeAnyIsDecoded) {
  json scene = facing_plane(0, 0, 5, 2, 40);
  const auto error = [&](const json& objects) {
    json s = scene;
    s["objects"] = objects;
    try {
      renderer(s);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const auto sphere_with = [](const std::string& texture, double x) {
    return json{{"type", "sphere"},
                {"center", {x, 0, 0}},
                {"radius", 0.5},
                {"material", {{"diffuse", {{"texture", texture}}}}}};
  };
  { std::ofstream(dir_ / "tall.png", std::ios::binary) << png_header_only(8192, 8193); }
  EXPECT_THAT(error(json::array({sphere_with("tall.png", 0)})),
              HasSubstr("texture tall.png: has 8192 x 8193 pixels, more than the 67108864"));
  // Five of the largest a texture may be: more than a scene's textures may be together.
  json five = json::array();
  for (int i = 0; i < 5; ++i) {
    const std::string name = "big" + std::to_string(i) + ".png";
    std::ofstream(dir_ / name, std::ios::binary) << png_header_only(8192, 8192);
    five.push_back(sphere_with(name, i));
  }
  EXPECT_THAT(error(five), HasSubstr("the scene's textures have 335544320 pixels together"));
  // The same file named twice counts once, as it is decoded once.
  json six = five;
  six.push_back(sphere_with("big0.png", 6));
  EXPECT_THAT(error(six), HasSubstr("the scene's textures have 335544320 pixels together"));
}

TEST_F(TextureTest, BadTexturesAreRefusedWithWhereAndWhy) {
  json scene = facing_plane(0, 0, 1, 1, 10);
  const auto error = [&](const json& material) {
    json s = scene;
    s["objects"] = json::array({plane_z(material)});
    try {
      renderer(s);
    } catch (const SceneError& e) {
      return std::string(e.what());
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(error({{"diffuse", {{"texture", "absent.png"}}}}), HasSubstr("absent.png"));
  EXPECT_THAT(error({{"diffuse", {{"texture", "absent.png"}}}}),
              HasSubstr("/objects/0/material/diffuse/texture"));
  write_texture("ok.exr", 2, 2, checker);
  EXPECT_THAT(error({{"diffuse", {{"texture", "ok.exr"}, {"wrap", "tile"}}}}),
              HasSubstr("/objects/0/material/diffuse/wrap"));
  EXPECT_THAT(error({{"diffuse", {{"texture", "ok.exr"}, {"size", 2}}}}),
              HasSubstr("/objects/0/material/diffuse"));
  EXPECT_THAT(error({{"diffuse", {{"texture", "ok.exr"}}}, {"checker", {{"size", 1}}}}),
              HasSubstr("/objects/0/material/checker"));
  std::filesystem::path bad = dir_ / "bad.png";
  { std::ofstream(bad) << "not an image at all"; }
  EXPECT_THAT(error({{"diffuse", {{"texture", "bad.png"}}}}), HasSubstr("bad.png"));
  // The farm's form with no farm to hold it.
  EXPECT_THAT(error({{"diffuse", {{"asset", "sha256:" + std::string(64, 'a')}}}}),
              HasSubstr("only the farm holds"));
  EXPECT_THAT(error({{"diffuse", {{"asset", "sha256:abc"}}}}), HasSubstr("64 lower-case hex"));
}

}  // namespace
}  // namespace tessera
