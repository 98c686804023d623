// The farm on the shapes people run it in, not only the one CI has: small tiles, workers of
// one thread and of many, and more threads than cores. Issue 29: with 8-px tiles the
// worker's uploads passed the coordinator's 256 tiles a result, were refused, and the
// same tiles were rendered again forever. Each shape must finish, give the local render's
// pixels bit for bit, and see no result refused on either side.
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

// 480x270 in 8-px tiles: 2,040 tiles, rendered in well under a second on 2 cores, so that
// finished tiles pile up far faster than one upload a few tens of milliseconds carries.
json many_small_tiles() { return test::showcase(480, 270, 1, 8); }

struct Shape {
  int workers;
  int threads;
};

void renders_like_the_local_render(const Shape& shape) {
  const std::string label = std::to_string(shape.workers) + "x" + std::to_string(shape.threads);
  SCOPED_TRACE(label);
  const json scene = many_small_tiles();
  const Image local = test::render_image(scene, 2);
  Farm farm("shape-" + label, shape.workers, {"--worker-threads", std::to_string(shape.threads)});
  const json job = farm.api().submit("shape " + label, 50, scene);
  // A stalled farm never finishes: the bound is far above what a working one needs here.
  const json done = farm.wait_finished(job["id"], 90s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, job["id"]), local));
  const json& health = done["health"];
  EXPECT_EQ(health["refused_results"], 0) << health.dump();
  EXPECT_EQ(health["tile_failures"], 0) << health.dump();
  EXPECT_EQ(health["repeated_handouts"], 0) << health.dump();
  // Both sides log a refused result: the coordinator as it answers, the worker (whose
  // output goes to the same log as a local worker) as it reads the answer.
  const std::string log = test::read_text(farm.dir() / "server.log");
  EXPECT_EQ(log.find("refused"), std::string::npos) << log.substr(0, 4000);
  EXPECT_EQ(log.find("duplicate result"), std::string::npos);
}

TEST(FarmShapesTest, TwoWorkersOfOneThreadWithEightPixelTiles) {
  renders_like_the_local_render({2, 1});
}

TEST(FarmShapesTest, OneWorkerOfTwoThreadsWithEightPixelTiles) {
  renders_like_the_local_render({1, 2});
}

// More threads than the machine has cores (CI has 2): uploads fall furthest behind.
TEST(FarmShapesTest, OneWorkerOfEightThreadsOnTwoCoresWithEightPixelTiles) {
  renders_like_the_local_render({1, 8});
}

}  // namespace
}  // namespace tessera
