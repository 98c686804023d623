// The farm end to end: a real tessera-server with real tessera-worker processes on
// loopback, driven over HTTP. The image a farm assembles must be bit-identical to a
// single machine's render of the same scene.
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>

#include "tests/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

using test::Farm;
using test::farm_image;
using test::small_showcase;

TEST(Farm, AnyWorkerCountAndTileSizeGivesTheLocalRenderBitForBit) {
  const struct {
    int workers, tile_size;
  } cases[] = {{1, 32}, {2, 8}, {3, 64}, {2, 32}};
  for (const auto& c : cases) {
    const json scene = small_showcase(c.tile_size);
    const Image local = test::render_image(scene, 2);
    Farm farm("bits-" + std::to_string(c.workers) + "-" + std::to_string(c.tile_size), c.workers);
    const json job = farm.api().submit("bits", 50, scene);
    const json done = farm.wait_finished(job["id"]);
    ASSERT_EQ(done["state"], "completed") << done.dump();
    const Image image = farm_image(farm, job["id"]);
    ASSERT_EQ(image.pixels().size(), local.pixels().size());
    EXPECT_EQ(std::memcmp(image.pixels().data(), local.pixels().data(), local.pixels().size_bytes()), 0)
        << c.workers << " workers, tile size " << c.tile_size;
  }
}

TEST(Farm, InvalidSceneIsRefusedWithItsPointerAndTheServerKeepsServing) {
  Farm farm("invalid", 0);
  json scene = small_showcase(32);
  scene["objects"][1]["radius"] = -1;
  try {
    farm.api().submit("bad", 50, scene);
    FAIL() << "accepted an invalid scene";
  } catch (const ApiError& e) {
    EXPECT_EQ(e.status(), 400);
    EXPECT_EQ(e.code(), "invalid_scene");
    EXPECT_EQ(e.path(), "/scene/objects/1/radius");
  }
  HttpClient http(farm.url(), 5s);
  const auto malformed = http.request("POST", "/v1/jobs", "{\"scene\": ");
  EXPECT_EQ(malformed.status, 400);
  EXPECT_NE(malformed.body.find("line 1"), std::string::npos) << malformed.body;
  EXPECT_EQ(http.request("GET", "/v1/nothing").status, 404);
  EXPECT_EQ(http.request("PUT", "/v1/jobs").status, 405);
  EXPECT_EQ(http.request("GET", "/healthz").status, 200);
}

TEST(Farm, CancelAndRemove) {
  Farm farm("cancel", 0);  // no workers: the job stays queued
  const json job = farm.api().submit("waiting", 50, small_showcase(32));
  const std::string id = job["id"];
  EXPECT_EQ(job["state"], "queued");
  try {
    farm.api().remove(id);
    FAIL() << "removed an active job";
  } catch (const ApiError& e) {
    EXPECT_EQ(e.status(), 409);
  }
  try {
    farm.api().image(id, "png", false);
    FAIL() << "served the image of an unfinished job";
  } catch (const ApiError& e) {
    EXPECT_EQ(e.status(), 409);
  }
  EXPECT_FALSE(farm.api().image(id, "png", true).empty());  // partial: all black so far
  EXPECT_EQ(farm.api().cancel(id)["state"], "canceled");
  farm.api().remove(id);
  try {
    farm.api().job(id);
    FAIL() << "removed job still there";
  } catch (const ApiError& e) {
    EXPECT_EQ(e.status(), 404);
  }
}

TEST(Farm, CliSubmitWaitWritesTheImage) {
  Farm farm("cli", 2);
  const fs::path scene = farm.dir() / "scene.json";
  std::ofstream(scene) << small_showcase(32).dump();
  const fs::path out = farm.dir() / "out.png";
  test::Process cli(TESSERA_CLI_BIN,
                    {"--server", farm.url(), "submit", scene.string(), "--wait", "-o", out.string()},
                    farm.dir() / "cli.log");
  const auto status = cli.wait_for(60s);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0);
  EXPECT_TRUE(fs::exists(out));

  // The server unreachable: exit code 3.
  test::Process offline(TESSERA_CLI_BIN, {"--server", "http://127.0.0.1:1", "list"},
                        farm.dir() / "offline.log");
  const auto offline_status = offline.wait_for(30s);
  ASSERT_TRUE(offline_status.has_value());
  EXPECT_EQ(WEXITSTATUS(*offline_status), 3);
}

}  // namespace
}  // namespace tessera
