// The farm end to end: a real tessera-server with real tessera-worker processes on
// loopback, driven over HTTP. The image a farm assembles must be bit-identical to a
// single machine's render of the same scene.
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

using test::Farm;
using test::farm_image;
using test::small_showcase;

TEST(FarmTest, AnyWorkerCountAndTileSizeGivesTheLocalRenderBitForBit) {
  const struct { int workers, tile_size; } cases[] = {{1, 32}, {2, 8}, {3, 64}, {2, 32}};
  for (const auto& c : cases) {
    const json scene = small_showcase(c.tile_size);
    const Image local = test::render_image(scene, 2);
    Farm farm("bits-" + std::to_string(c.workers) + "-" + std::to_string(c.tile_size), c.workers);
    const json job = farm.api().submit("bits", 50, scene);
    const json done = farm.wait_finished(job["id"]);
    ASSERT_EQ(done["state"], "completed") << done.dump();
    const Image image = farm_image(farm, job["id"]);
    ASSERT_EQ(image.pixels().size(), local.pixels().size());
    EXPECT_EQ(
        std::memcmp(image.pixels().data(), local.pixels().data(), local.pixels().size_bytes()), 0)
        << c.workers << " workers, tile size " << c.tile_size;
    // Every tile rendered once: a worker that renders a tile twice shows up as a duplicate.
    EXPECT_EQ(test::read_text(farm.dir() / "server.log").find("duplicate result"),
              std::string::npos)
        << c.workers << " workers, tile size " << c.tile_size;
  }
}

// The job keeps its scene's output transfer from submission (the job row), so its PNG is
// encoded as the local render's is, each way.
TEST(FarmTest, APngDownloadIsEncodedWithTheScenesOutputTransfer) {
  Farm farm("transfer", 1);
  for (const char* transfer : {"linear", "srgb"}) {
    json scene = small_showcase(32);
    scene["render"]["output_transfer"] = transfer;
    const Image local = test::render_image(scene, 2);
    const auto local_png = farm.dir() / (std::string("local-") + transfer + ".png");
    write_image(local, local_png,
                std::string(transfer) == "linear" ? OutputTransfer::linear : OutputTransfer::srgb);
    const std::string id = farm.api().submit(transfer, 50, scene)["id"];
    ASSERT_EQ(farm.wait_finished(id)["state"], "completed");
    EXPECT_EQ(farm.api().image(id, "png", false), test::read_text(local_png)) << transfer;
  }
}

TEST(FarmTest, InvalidSceneIsRefusedWithItsPointerAndTheServerKeepsServing) {
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
  HttpClient http = farm.http(5s);
  const auto malformed = http.request("POST", "/v1/jobs", "{\"scene\": ");
  EXPECT_EQ(malformed.status, 400);
  EXPECT_NE(malformed.body.find("line 1"), std::string::npos) << malformed.body;
  EXPECT_EQ(http.request("GET", "/v1/nothing").status, 404);
  EXPECT_EQ(http.request("PUT", "/v1/jobs").status, 405);
  EXPECT_EQ(http.request("GET", "/healthz").status, 200);
}

TEST(FarmTest, CancelAndRemove) {
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

TEST(FarmTest, CliSubmitWaitWritesTheImage) {
  Farm farm("cli", 2);
  const fs::path scene = farm.dir() / "scene.json";
  std::ofstream(scene) << small_showcase(32).dump();
  const fs::path out = farm.dir() / "out.png";
  test::Process cli(
      TESSERA_CLI_BIN,
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

TEST(FarmTest, SigtermStopsTheServerCleanlyAndDeliveredTilesSurviveARestart) {
  const fs::path dir = test::fresh_dir("restart");
  const json scene =
      test::showcase(160, 120, 96, 16);  // 80 tiles, ~1.5 s for one thread: far longer than a poll
  auto start_server = [&](const std::string& name) {
    fs::remove(dir / "port");
    auto server = std::make_unique<test::Process>(
        TESSERA_SERVER_BIN,
        std::vector<std::string>{"--listen", "127.0.0.1:0", "--data-dir", (dir / "data").string(),
                                 "--local-workers", "0", "--port-file", (dir / "port").string(),
                                 "--log-level", "info"},
        dir / (name + ".log"));
    EXPECT_TRUE(test::eventually([&] { return fs::exists(dir / "port"); }, 20s));
    int port = 0;
    std::ifstream(dir / "port") >> port;
    return std::pair{std::move(server), "http://127.0.0.1:" + std::to_string(port)};
  };
  auto start_worker = [&](const std::string& url, const std::string& name) {
    return std::make_unique<test::Process>(
        TESSERA_WORKER_BIN,
        std::vector<std::string>{"--server", url, "--threads", "1", "--name", name},
        dir / (name + ".log"));
  };

  auto [server, url] = start_server("first");
  test::JsonApi api(url);
  const std::string id = api.submit("restart", 50, scene)["id"];
  auto worker = start_worker(url, "before");
  ASSERT_TRUE(test::eventually([&] { return api.job(id)["tiles"]["done"].get<int>() >= 10; }, 60s));
  worker->signal(SIGTERM);
  ASSERT_TRUE(worker->wait_for(30s).has_value());
  const int delivered = api.job(id)["tiles"]["done"];
  ASSERT_LT(delivered, 80) << "the job finished before the restart; make it bigger";

  server->signal(SIGTERM);
  const auto status = server->wait_for(20s);
  ASSERT_TRUE(status.has_value()) << "the server did not stop on SIGTERM";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0);

  auto [again, url2] = start_server("second");
  test::JsonApi api2(url2);
  const json resumed = api2.job(id);
  EXPECT_EQ(resumed["tiles"]["done"], delivered) << "tiles delivered before the stop were lost";
  auto finisher = start_worker(url2, "after");
  ASSERT_TRUE(test::eventually([&] { return api2.job(id)["state"] == "completed"; }, 60s));
  const fs::path exr = dir / "restart.exr";
  test::write_text(exr, api2.image(id, "exr", false));
  EXPECT_TRUE(test::same_pixels(read_image(exr), test::render_image(scene, 2)));
  finisher->signal(SIGTERM);
  finisher->wait_for(30s);
  again->signal(SIGTERM);
  again->wait_for(20s);
}

TEST(FarmTest, ALocalWorkerThatDiesIsReplaced) {
  Farm farm("respawn", 1);
  std::vector<pid_t> before;
  ASSERT_TRUE(test::eventually(
      [&] { return (before = test::children_of(farm.server().pid())).size() == 1; }, 20s));
  ::kill(before[0], SIGKILL);
  std::vector<pid_t> after;
  ASSERT_TRUE(test::eventually(
      [&] {
        after = test::children_of(farm.server().pid());
        return after.size() == 1 && after[0] != before[0];
      },
      20s))
      << "no replacement worker was started";
  // The replacement renders.
  const json job = farm.api().submit("after-respawn", 50, small_showcase(32));
  EXPECT_EQ(farm.wait_finished(job["id"])["state"], "completed");
}

}  // namespace
}  // namespace tessera
