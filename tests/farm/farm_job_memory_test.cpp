// What a job may cost the coordinator's memory: its tiles are budgeted (--max-job-tiles,
// --job-memory-budget) and refused past the budget with the limit named, the tiles of a
// job of a million are read a page at a time in bounded memory, and a coordinator whose
// store holds more than its budget still starts, fails what it cannot hold and serves.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

// A one-sphere scene of `size` squared pixels in 8-pixel tiles: (size / 8)^2 tiles.
json sphere_scene(int size) {
  json scene = json::parse(R"({"version": 1,
    "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45},
    "materials": {"m": {"diffuse": [1, 0, 0]}},
    "lights": [{"type": "point", "position": [0, 5, 5], "intensity": [1, 1, 1]}],
    "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]})");
  scene["image"] = {{"width", size}, {"height", size}};
  scene["render"] = {{"tile_size", 8}, {"samples_per_pixel", 1}};
  return scene;
}

std::int64_t rss_kib(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stoll(line.substr(6));
  return -1;
}

HttpResult submit(HttpClient& http, const json& scene) {
  return http.request("POST", "/v1/jobs", json{{"name", "big"}, {"scene", scene}}.dump());
}

TEST(FarmJobMemoryTest, JobsAreBudgetedTheirTilesPagedAndAStartOverTheBudgetServes) {
  const fs::path dir = test::fresh_dir("job-memory");
  const auto start = [&](const std::string& budget, const std::string& log) {
    fs::remove(dir / "port");
    auto server = std::make_unique<test::Process>(
        TESSERA_SERVER_BIN,
        std::vector<std::string>{"--listen", "127.0.0.1:0", "--data-dir", (dir / "data").string(),
                                 "--local-workers", "0", "--port-file", (dir / "port").string(),
                                 "--job-memory-budget", budget, "--log-level", "info"},
        dir / log);
    const int port = test::port_from_file(dir, dir / log);
    return std::make_pair(std::move(server), "http://127.0.0.1:" + std::to_string(port));
  };
  // 200 MB: one job of 2^20 tiles (128 MiB reckoned) fits, a second does not.
  auto [server, url] = start("200000000", "server.log");
  HttpClient http(url, 30s);
  // Over --max-job-tiles (4,194,304 by default): a 32768-pixel square at 8-pixel tiles.
  // The width limit is raised by nothing here, so ask within it: 16384 at 4-pixel tiles.
  json over_tiles = sphere_scene(16384);
  over_tiles["render"]["tile_size"] = 4;
  const HttpResult too_many = submit(http, over_tiles);
  ASSERT_EQ(too_many.status, 422) << too_many.body;
  EXPECT_EQ(json::parse(too_many.body)["error"]["limit"], "max_job_tiles");
  EXPECT_NE(too_many.body.find("--max-job-tiles"), std::string::npos) << too_many.body;

  const std::int64_t idle = rss_kib(server->pid());
  const HttpResult first = submit(http, sphere_scene(8192));  // 1,048,576 tiles
  ASSERT_EQ(first.status, 201) << first.body;
  // Compact tiles: what the job costs stays within what the budget reckons, 128 bytes a
  // tile (it was about 230 while each tile held its own strings and rectangle).
  const std::int64_t held = rss_kib(server->pid()) - idle;
  EXPECT_LT(held, 128 * 1024) << "a job of 1,048,576 tiles took " << held << " KiB";
  const std::string id = json::parse(first.body)["id"];
  const HttpResult second = submit(http, sphere_scene(8192));
  ASSERT_EQ(second.status, 422) << second.body;
  const json refusal = json::parse(second.body)["error"];
  EXPECT_EQ(refusal["limit"], "job_memory_budget");
  EXPECT_EQ(refusal["limit_value"], 200000000);
  EXPECT_NE(refusal["message"].get<std::string>().find("--job-memory-budget"), std::string::npos)
      << second.body;
  // Smaller jobs still fit beside it.
  EXPECT_EQ(submit(http, sphere_scene(64)).status, 201);

  // The tiles a page at a time: the first, one in the middle, the last.
  const std::int64_t before = rss_kib(server->pid());
  const HttpResult page = http.request("GET", "/v1/jobs/" + id + "/tiles");
  ASSERT_EQ(page.status, 200);
  const json list = json::parse(page.body);
  EXPECT_EQ(list["tiles"].size(), 10000u);
  EXPECT_EQ(list["total"], 1048576);
  EXPECT_EQ(list["next_offset"], 10000);
  EXPECT_EQ(list["tiles"][0]["index"], 0);
  const json middle =
      json::parse(http.request("GET", "/v1/jobs/" + id + "/tiles?offset=500000&limit=3").body);
  ASSERT_EQ(middle["tiles"].size(), 3u);
  EXPECT_EQ(middle["tiles"][2]["index"], 500002);
  EXPECT_EQ(middle["next_offset"], 500003);
  const json last =
      json::parse(http.request("GET", "/v1/jobs/" + id + "/tiles?offset=1048570").body);
  EXPECT_EQ(last["tiles"].size(), 6u);
  EXPECT_TRUE(last["next_offset"].is_null());
  EXPECT_EQ(http.request("GET", "/v1/jobs/" + id + "/tiles?limit=10001").status, 400);
  // Every page of the job read: memory stays where it was (a whole list was 155 MB).
  for (int offset = 0; offset < 1048576; offset += 10000 * 16)
    ASSERT_EQ(
        http.request("GET", "/v1/jobs/" + id + "/tiles?offset=" + std::to_string(offset)).status,
        200);
  EXPECT_LT(rss_kib(server->pid()) - before, 64 * 1024)
      << "RSS grew from " << before << " KiB while the tiles were read";

  // A budget lowered below what the store holds: the coordinator starts and serves; the
  // job it cannot hold is failed, saying why, and can be removed.
  server->signal(SIGTERM);
  ASSERT_TRUE(server->wait_for(30s).has_value());
  auto [lowered, lowered_url] = start("100000000", "server-lowered.log");
  HttpClient again(lowered_url, 30s);
  EXPECT_EQ(again.request("GET", "/healthz").status, 200);
  const json job = json::parse(again.request("GET", "/v1/jobs/" + id).body);
  EXPECT_EQ(job["state"], "failed") << job.dump();
  EXPECT_NE(job["error"].get<std::string>().find("not loaded at start"), std::string::npos)
      << job.dump();
  EXPECT_NE(job["error"].get<std::string>().find("--job-memory-budget"), std::string::npos)
      << job.dump();
  EXPECT_EQ(again.request("DELETE", "/v1/jobs/" + id).status, 204);
  EXPECT_EQ(again.request("GET", "/v1/jobs/" + id).status, 404);
  // And with the budget back, the store has room again.
  EXPECT_EQ(submit(again, sphere_scene(4096)).status, 201);
  lowered->signal(SIGTERM);
  EXPECT_TRUE(lowered->wait_for(30s).has_value());
}

}  // namespace
}  // namespace tessera
