// A pixel's value depends only on the scene and the pixel: never on tile size, tile order
// or thread count. Checked bit for bit.
#include <cmath>
#include <cstring>
#include <numbers>

#include <gtest/gtest.h>

#include "tests/unit/worker/render_helpers.hpp"
#include "tracer/pixel_sampler.hpp"

namespace tessera {
namespace {

using test::json;

// A torus as an inline mesh, with its normals when `smooth`.
json torus(double major, double minor, bool smooth) {
  constexpr int around = 24, across = 12;
  json positions = json::array(), normals = json::array(), triangles = json::array();
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < across; ++j) {
      const double u = 2 * std::numbers::pi * i / around;
      const double v = 2 * std::numbers::pi * j / across;
      positions.push_back({(major + minor * std::cos(v)) * std::cos(u), minor * std::sin(v),
                           (major + minor * std::cos(v)) * std::sin(u)});
      normals.push_back({std::cos(v) * std::cos(u), std::sin(v), std::cos(v) * std::sin(u)});
      const auto at = [](int a, int b) { return ((a % around) * across) + (b % across); };
      triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
    }
  json mesh = {{"type", "mesh"}, {"positions", positions}, {"triangles", triangles}};
  if (smooth) mesh["normals"] = normals;
  return mesh;
}

TEST(DeterminismTest, CompactMeshesGiveTheBitsOfMeshesThatKeepTheirCorners) {
  // Meshes above kCompactMeshTriangles read their corners through Embree's buffers; with the
  // threshold at 0 every mesh does, and every pixel must keep its bits: smooth and flat,
  // mirrored by their transform, opaque and glass (whose bounds the shadow rays test).
  json scene = test::busy_scene();
  json smooth = torus(0.6, 0.2, true);
  smooth["material"] = "mirror";
  smooth["transform"] = {{{"rotate", {{"axis", {1, 0, 0}}, {"degrees", 60}}}},
                         {{"translate", {0.3, 1.4, -0.5}}}};
  json mirrored = torus(0.5, 0.18, true);
  mirrored["material"] = "glass";
  mirrored["transform"] = {{{"scale", {-1, 1, 1}}}, {{"translate", {1.6, 1.8, 0.8}}}};
  json flat = torus(0.4, 0.15, false);
  flat["transform"] = {{{"translate", {-1.5, 2.2, 0.5}}}};
  scene["objects"].push_back(smooth);
  scene["objects"].push_back(mirrored);
  scene["objects"].push_back(flat);
  const Renderer kept(parse_scene(scene));
  const Renderer compact(parse_scene(scene), {0, false});
  // Embree holds the meshes; the scene's own arrays of them were freed.
  EXPECT_TRUE(std::get<Mesh>(kept.scene().objects.back().shape).positions.empty());
  EXPECT_TRUE(std::get<Mesh>(kept.scene().objects.back().shape).triangles.empty());
  const Image reference = render_local(kept, 2, 16).image;
  const Image image = render_local(compact, 2, 16).image;
  ASSERT_EQ(image.pixels().size(), reference.pixels().size());
  EXPECT_EQ(std::memcmp(image.pixels().data(), reference.pixels().data(),
                        reference.pixels().size_bytes()),
            0);
  // The meshes are in the picture: without them it differs.
  const Image without = render_local(Renderer(parse_scene(test::busy_scene())), 2, 16).image;
  EXPECT_NE(std::memcmp(without.pixels().data(), reference.pixels().data(),
                        reference.pixels().size_bytes()),
            0);
}

TEST(DeterminismTest, BitIdenticalForAnyTileSizeAndThreadCount) {
  const Renderer renderer(parse_scene(test::busy_scene()));
  const Image reference = render_local(renderer, 1, 32).image;
  for (int tile_size : {1, 7, 32, 64})
    for (int threads : {1, 2}) {
      const Image image = render_local(renderer, threads, tile_size).image;
      ASSERT_EQ(image.pixels().size(), reference.pixels().size());
      EXPECT_EQ(std::memcmp(image.pixels().data(), reference.pixels().data(),
                            reference.pixels().size_bytes()),
                0)
          << "tile size " << tile_size << ", " << threads << " threads";
    }
}

TEST(DeterminismTest, PacketsOfPrimaryRaysGiveTheBitsOfSingleRays) {
  // render_tile intersects primary rays, and their shadow rays, sixteen at a time; the
  // tracer's single-ray path must give every pixel the very same bits.
  json scene = test::busy_scene();
  scene["render"]["samples_per_pixel"] = 1;
  const Renderer renderer(parse_scene(scene));
  const Image image = render_local(renderer, 1, 16).image;
  int differing = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      RayCounts counts;
      const Color single =
          renderer.tracer().trace(renderer.camera().ray_through(x + 0.5, y + 0.5), 0, counts);
      const float* pixel = image.pixel(x, y);
      differing += pixel[0] != static_cast<float>(single.r) ||
                   pixel[1] != static_cast<float>(single.g) ||
                   pixel[2] != static_cast<float>(single.b);
    }
  EXPECT_EQ(differing, 0) << "of " << image.width() * image.height() << " pixels";
}

TEST(DeterminismTest, PacketsOfSeveralSamplesGiveTheBitsOfSingleRays) {
  // With several samples, render_tile makes each sample's sixteen camera rays at once; every
  // pixel must still be the mean of single rays through sample_offset()'s positions, summed
  // in sample order and divided as render_tile divides (by a reciprocal for powers of two).
  for (int samples : {3, 4}) {
    json scene = test::busy_scene();
    scene["render"]["samples_per_pixel"] = samples;
    const Renderer renderer(parse_scene(scene));
    const Image image = render_local(renderer, 1, 16).image;
    int differing = 0;
    for (int y = 0; y < image.height(); ++y)
      for (int x = 0; x < image.width(); ++x) {
        Color sum(0.0);
        for (int s = 0; s < samples; ++s) {
          RayCounts counts;
          const SampleOffset offset = sample_offset(x, y, s, samples);
          sum += renderer.tracer().trace(renderer.camera().ray_through(x + offset.x, y + offset.y),
                                         0, counts);
        }
        const Color mean = samples == 4 ? sum * 0.25 : sum / static_cast<double>(samples);
        const float* pixel = image.pixel(x, y);
        differing += pixel[0] != static_cast<float>(mean.r) ||
                     pixel[1] != static_cast<float>(mean.g) ||
                     pixel[2] != static_cast<float>(mean.b);
      }
    EXPECT_EQ(differing, 0) << "of " << image.width() * image.height() << " pixels, " << samples
                            << " samples";
  }
}

TEST(DeterminismTest, CameraPacketsHaveTheBitsOfSingleRays) {
  const Renderer renderer(parse_scene(test::busy_scene()));
  const PinholeCamera& camera = renderer.camera();
  // Positions anywhere on the image plane and a little beyond it, as edge blocks have.
  double x[kPacketSize];
  double y[kPacketSize];
  float direction[3][kPacketSize];
  for (int round = 0; round < 64; ++round) {
    for (int i = 0; i < kPacketSize; ++i) {
      x[i] = (round * kPacketSize + i) * 0.0371 - 1.3;
      y[i] = (round * 7 + i * 3) * 0.113 - 0.9;
    }
    camera.directions_through(x, y, direction);
    for (int i = 0; i < kPacketSize; ++i) {
      const Ray single = camera.ray_through(x[i], y[i]);
      for (int axis = 0; axis < 3; ++axis)
        ASSERT_EQ(direction[axis][i], single.direction[axis])
            << "position (" << x[i] << ", " << y[i] << "), axis " << axis;
      EXPECT_EQ(camera.origin(), single.origin);
    }
  }
}

TEST(DeterminismTest, ATileRenderedAloneMatchesTheWholeImage) {
  // As when a worker on another machine, with a freshly built BVH, renders one tile.
  const json scene = test::busy_scene();
  const Image whole = render_local(Renderer(parse_scene(scene)), 2, 16).image;
  const Renderer fresh(parse_scene(scene));
  const TileRect tile{23, 11, 19, 13};
  std::vector<float> pixels(tile.pixel_count() * 3);
  fresh.render_tile(tile, pixels);
  for (int y = 0; y < tile.height; ++y)
    EXPECT_EQ(std::memcmp(&pixels[y * tile.width * 3], whole.pixel(tile.x, tile.y + y),
                          tile.width * 3 * sizeof(float)),
              0)
        << "row " << y;
}

TEST(DeterminismTest, SamplesSpreadOverThePixelAndAverageEqually) {
  // The edge of an emitting box runs down the middle of the left pixel: with 64 samples
  // spread over the pixel, about half hit it.
  json scene = {{"image", {{"width", 2}, {"height", 1}}},
                {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}}},
                {"ambient_light", 0},
                {"render", {{"samples_per_pixel", 64}}},
                {"objects",
                 {{{"type", "box"},
                   {"min", {0, -10, -1}},
                   {"max", {10, 10, 0}},
                   {"transform", {{{"translate", {-2.0710678, 0, 0}}}}},
                   {"material", {{"ambient", 0}, {"diffuse", 0}, {"emission", 1}}}}}}};
  // At z = 0 the view spans x in ±2·5·tan(22.5°) = ±4.142, so the left pixel's middle is
  // x = -2.071.
  const Image image = test::render_image(scene);
  EXPECT_NEAR(image.pixel(0, 0)[0], 0.5, 0.05);
  EXPECT_EQ(image.pixel(1, 0)[0], 1.0f);
}

}  // namespace
}  // namespace tessera
