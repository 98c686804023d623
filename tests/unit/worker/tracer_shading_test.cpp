// The tracer's cheaper forms of its per-hit steps, each against the plain form it replaces,
// and the strided tile output of render_tile.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/worker/render_helpers.hpp"
#include "tracer/tracer_shading.hpp"

namespace tessera {
namespace {

using shading_detail::in_odd_checker_cell;
using shading_detail::power;
using test::json;

TEST(PowerTest, WholeExponentsBySquaringAgreeWithPow) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const double base = unit(random);
    for (double exponent : {1.0, 2.0, 3.0, 7.0, 20.0, 50.0, 128.0, 300.0, 4096.0}) {
      const double expected = std::pow(base, exponent);
      // Each squaring doubles the relative error it is handed, so b^n is good to about n
      // units in the last place: 1e-12 at n = 4096, far below anything a pixel shows.
      const double tolerance = 4.0 * exponent * std::numeric_limits<double>::epsilon();
      EXPECT_NEAR(power(base, exponent), expected, tolerance * expected) << base << "^" << exponent;
    }
  }
  EXPECT_EQ(power(0.0, 0.0), 1.0);  // as pow() has it: K_S·(V·R)^0 is K_S
  EXPECT_EQ(power(0.3, 0.0), 1.0);
  EXPECT_EQ(power(0.0, 5.0), 0.0);
  EXPECT_EQ(power(1.0, 4096.0), 1.0);
  EXPECT_EQ(power(0.5, 3.0), 0.125);  // exact: squaring rounds nothing here
  // Fractional and very large exponents are pow()'s own.
  EXPECT_EQ(power(0.7, 2.5), std::pow(0.7, 2.5));
  EXPECT_EQ(power(0.999, 1e6), std::pow(0.999, 1e6));
}

// The parity of the cell by std::floor, as in_odd_checker_cell's slow path has it.
bool odd_by_floor(const Vec3& position, const Vec3& normal, double size) {
  const Vec3 p = position * (1.0 / size) - 1e-4 * normal;
  const double sum = std::floor(p.x) + std::floor(p.y) + std::floor(p.z);
  return std::fmod(std::fabs(sum), 2.0) == 1.0;
}

SurfaceHit hit_at(const Vec3& position, const Vec3& normal) {
  SurfaceHit hit{};
  hit.position = position;
  hit.normal = normal;
  hit.shading_normal = normal;
  return hit;
}

TEST(CheckerTest, IntegerCellParityIsFloorsParity) {
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> coordinate(-50.0, 50.0);
  std::uniform_int_distribution<int> integer(-40, 40);
  const Vec3 normals[] = {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}, glm::normalize(Vec3(1, 2, -3))};
  for (int trial = 0; trial < 20000; ++trial) {
    const double size = trial % 2 ? 0.7 : 1.0;
    // Half the points lie on cell boundaries, where the offset below the surface decides.
    Vec3 p(coordinate(random), coordinate(random), coordinate(random));
    if (trial % 4 < 2) p.y = integer(random) * size;
    const Vec3& n = normals[trial % 4];
    EXPECT_EQ(in_odd_checker_cell(1.0 / size, hit_at(p, n)), odd_by_floor(p, n, size))
        << p.x << " " << p.y << " " << p.z << " size " << size;
  }
}

TEST(CheckerTest, BeyondTwoToTheFiftyTwoCellsFloorDecides) {
  // Every double this large is an integer, too large for the integer path: the floor path
  // answers, and agrees with the same parity by floor.
  const Vec3 n(0, 1, 0);
  for (const double x : {0x1p53, 0x1p53 + 2.0, -0x1p60, 3e20}) {
    const Vec3 p(x, 0.5, 0.25);
    EXPECT_EQ(in_odd_checker_cell(1.0, hit_at(p, n)), odd_by_floor(p, n, 1.0)) << x;
  }
}

TEST(ShadowRaysTest, ALightOnAWallFacingTheFloorLightsIt) {
  // The floor lies at y = 100, so its shadow rays start 256 units in the last place above it
  // (2e-3): towards the light by 1.4e-3 of its 1.41 distance, a hundred times the 1e-5 by
  // which a shadow ray stops short. Measured from the surface point, the ray's reach would
  // run past the light into the wall it sits on; it must be measured from the ray's start.
  json scene = test::pinhole_scene({0, 101, 3}, {0, 100, 3}, {0, 0, -1});
  scene["objects"].push_back({{"type", "plane"},
                              {"point", {0, 100, 0}},
                              {"normal", {0, 1, 0}},
                              {"material", {{"ambient", 0}, {"diffuse", 0.8}}}});
  // Square to the light's direction from the floor point, (1, 1, 0)/√2.
  scene["objects"].push_back({{"type", "plane"},
                              {"point", {1, 101, 3}},
                              {"normal", {-1, -1, 0}},
                              {"material", {{"ambient", 0}, {"diffuse", 0.5}}}});
  scene["lights"].push_back({{"type", "point"}, {"position", {1, 101, 3}}});
  // N·L = cos 45°, no attenuation.
  EXPECT_NEAR(test::render_pixel(scene).r, 0.8 / std::sqrt(2.0), 1e-5);
}

// Packets of shadow rays test opaque planes outside Embree (SceneGeometry::occluded); a
// plane between a point and the light must still block it there.
TEST(ShadowRaysTest, AnOpaquePlaneBetweenAPointAndTheLightShadowsIt) {
  json scene = test::pinhole_scene({2, 3, 0}, {2, 0, 0}, {0, 0, -1});
  scene["objects"].push_back({{"type", "plane"},
                              {"point", {0, 0, 0}},
                              {"normal", {0, 1, 0}},
                              {"material", {{"ambient", 0}, {"diffuse", 0.8}}}});
  scene["lights"].push_back({{"type", "point"}, {"position", {-1, 2, 0}}});
  EXPECT_GT(test::render_pixel(scene).r, 0.1);  // lit while nothing is in the way
  json walled = scene;
  walled["objects"].push_back({{"type", "plane"},
                               {"point", {0, 0, 0}},
                               {"normal", {1, 0, 0}},
                               {"material", {{"ambient", 0}, {"diffuse", 0.5}}}});
  EXPECT_EQ(test::render_pixel(walled).r, 0.0);
  // And the light on the near side of that wall reaches the point again.
  walled["lights"][0]["position"] = {1, 2, 0};
  EXPECT_GT(test::render_pixel(walled).r, 0.1);
}

TEST(RenderTileTest, WritesIntoRowsOfALargerImageAndNothingElse) {
  json scene = test::pinhole_scene({0, 0, 5}, {0, 0, 0});
  scene["image"] = {{"width", 24}, {"height", 20}};
  scene["ambient_light"] = 1;
  scene["objects"].push_back({{"type", "sphere"},
                              {"center", {0, 0, 0}},
                              {"radius", 1},
                              {"material", {{"checker", {{"size", 0.3}, {"ambient", 0.1}}}}}});
  const Renderer renderer(parse_scene(scene));
  const TileRect tile{5, 3, 13, 9};
  std::vector<float> tight(tile.pixel_count() * 3);
  renderer.render_tile(tile, tight);

  const std::size_t stride = 24 * 3;
  constexpr float kUntouched = -7.0f;
  std::vector<float> image(20 * stride, kUntouched);
  const std::size_t first = tile.y * stride + tile.x * 3;
  renderer.render_tile(tile, std::span<float>(image).subspan(first), stride);
  std::size_t written = 0;
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 24; ++x) {
      const float* pixel = &image[y * stride + x * 3];
      const bool inside =
          x >= tile.x && x < tile.x + tile.width && y >= tile.y && y < tile.y + tile.height;
      if (!inside) {
        EXPECT_EQ(pixel[0], kUntouched) << x << "," << y;
        continue;
      }
      const float* expected =
          &tight[((y - tile.y) * tile.width + (x - tile.x)) * static_cast<std::size_t>(3)];
      EXPECT_EQ(std::memcmp(pixel, expected, 3 * sizeof(float)), 0) << x << "," << y;
      ++written;
    }
  EXPECT_EQ(written, tile.pixel_count());

  // One float short of the tile's last pixel, or rows closer than a tile's width: refused.
  const std::size_t needed = (tile.height - 1) * stride + tile.width * 3;
  std::vector<float> short_buffer(needed - 1);
  EXPECT_THROW(renderer.render_tile(tile, short_buffer, stride), std::invalid_argument);
  EXPECT_THROW(renderer.render_tile(tile, image, tile.width * 3 - 1), std::invalid_argument);
}

}  // namespace
}  // namespace tessera
