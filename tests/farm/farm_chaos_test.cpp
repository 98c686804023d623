// Chaos: several jobs render while workers and the coordinator are killed with SIGKILL and
// started again, over and over, at moments drawn from a seeded generator. At the end every
// job is completed with the image of a render without the chaos. Bounded: the chaos stops
// when the jobs are done or after 45 s.
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

TEST(FarmChaosTest, JobsCompleteWithTheRightImageWhileWorkersAndTheCoordinatorAreKilled) {
  const fs::path dir = test::fresh_dir("chaos");
  const unsigned seed = 20261201;
  std::mt19937 random(seed);
  int port = 0;
  int coordinator_starts = 0;
  const auto start_coordinator = [&] {
    fs::remove(dir / "port");
    auto server = std::make_unique<test::Process>(
        TESSERA_SERVER_BIN,
        std::vector<std::string>{
            "--listen", "127.0.0.1:" + std::to_string(port), "--data-dir", (dir / "data").string(),
            "--local-workers", "0", "--port-file", (dir / "port").string(), "--lease-timeout", "1",
            "--heartbeat-interval", "0.2",
            // A kill charges the tiles of the leases it ends, and sends
            // them out again: many kills must not add up to a failed job.
            "--max-tile-attempts", "1000", "--max-tile-handouts", "1000", "--log-level", "info"},
        dir / ("coordinator-" + std::to_string(++coordinator_starts) + ".log"));
    EXPECT_TRUE(test::eventually([&] { return fs::exists(dir / "port"); }, 20s))
        << "the coordinator did not start";
    std::ifstream(dir / "port") >> port;
    return server;
  };
  auto coordinator = start_coordinator();
  const std::string url = "http://127.0.0.1:" + std::to_string(port);

  int worker_starts = 0;
  const auto start_worker = [&](int slot) {
    return std::make_unique<test::Process>(
        TESSERA_WORKER_BIN,
        std::vector<std::string>{"--server", url, "--threads", "1", "--name",
                                 "chaos-" + std::to_string(slot)},
        dir / ("worker-" + std::to_string(++worker_starts) + ".log"));
  };
  std::vector<std::unique_ptr<test::Process>> workers;
  for (int slot = 0; slot < 3; ++slot) workers.push_back(start_worker(slot));

  const json scene = test::showcase(480, 360, 16, 32);  // 180 tiles a job
  std::vector<std::string> jobs;
  {
    test::JsonApi api(url);
    for (int i = 0; i < 3; ++i)
      jobs.push_back(api.submit("chaos-" + std::to_string(i), 40 + 10 * i, scene)["id"]);
  }
  // Whether every job has completed, asked of whichever coordinator is up; false while
  // none answers.
  const auto all_completed = [&] {
    try {
      test::JsonApi api(url);
      for (const std::string& id : jobs)
        if (api.job(id)["state"] != "completed") return false;
      return true;
    } catch (const HttpError&) {
      return false;
    }
  };

  int worker_kills = 0;
  int coordinator_kills = 0;
  const auto chaos_end = Clock::now() + 45s;
  std::uniform_int_distribution<int> pause_ms(150, 600);
  std::uniform_int_distribution<int> percent(0, 99);
  std::uniform_int_distribution<int> slot_of(0, 2);
  while (Clock::now() < chaos_end && !all_completed()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms(random)));
    if (percent(random) < 70) {
      const int slot = slot_of(random);
      workers[slot]->signal(SIGKILL);
      ASSERT_TRUE(workers[slot]->wait_for(10s).has_value());
      workers[slot] = start_worker(slot);  // the same name again, as a restarted machine
      ++worker_kills;
    } else {
      coordinator->signal(SIGKILL);
      ASSERT_TRUE(coordinator->wait_for(10s).has_value());
      coordinator = start_coordinator();
      ++coordinator_kills;
    }
  }
  std::printf("chaos (seed %u): survived %d worker kills and %d coordinator kills\n", seed,
              worker_kills, coordinator_kills);
  RecordProperty("worker_kills", worker_kills);
  RecordProperty("coordinator_kills", coordinator_kills);
  EXPECT_GE(worker_kills + coordinator_kills, 5)
      << "too little chaos to mean anything: make the jobs bigger";

  ASSERT_TRUE(test::eventually(all_completed, 60s)) << "not every job completed; see " << dir;
  const Image expected = test::render_image(scene, 2);
  test::JsonApi api(url);
  for (const std::string& id : jobs) {
    const json job = api.job(id);
    EXPECT_EQ(job["tiles"]["done"], job["tiles"]["total"]) << job.dump();
    const fs::path exr = dir / (id + ".exr");
    test::write_text(exr, api.image(id, "exr", false));
    EXPECT_TRUE(test::same_pixels(read_image(exr), expected)) << id;
  }
  for (auto& worker : workers) worker->signal(SIGTERM);
  for (auto& worker : workers) worker->wait_for(20s);
  coordinator->signal(SIGTERM);
  coordinator->wait_for(20s);
}

}  // namespace
}  // namespace tessera
