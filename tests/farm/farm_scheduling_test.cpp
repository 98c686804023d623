// Scheduling with real tessera-worker processes: priorities decide the order, a worker that
// joins late gets a share, and a worker stopped with SIGTERM delivers its tile instead of
// leaving it stranded under a lease. Each farm image is compared bit for bit with a local
// render: whoever renders a tile, the pixels are the same.
#include <ctime>
#include <thread>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

// "2024-05-01T12:34:56.789Z" (the API's timestamps) as milliseconds since the epoch.
std::int64_t epoch_ms(const json& timestamp) {
  if (!timestamp.is_string()) throw std::runtime_error("not a timestamp: " + timestamp.dump());
  const std::string text = timestamp;
  std::tm utc{};
  int ms = 0;
  if (std::sscanf(text.c_str(), "%d-%d-%dT%d:%d:%d.%dZ", &utc.tm_year, &utc.tm_mon, &utc.tm_mday,
                  &utc.tm_hour, &utc.tm_min, &utc.tm_sec, &ms) != 7)
    throw std::runtime_error("not a timestamp: " + text);
  utc.tm_year -= 1900;
  utc.tm_mon -= 1;
  return static_cast<std::int64_t>(::timegm(&utc)) * 1000 + ms;
}

TEST(FarmSchedulingTest, TheHigherPriorityJobIsRenderedFirst) {
  Farm farm("sched-priority", 0);
  const json scene = test::showcase(96, 64, 2, 16);  // 24 tiles each
  // Submitted first, so plain submission order would favour it.
  const std::string low = farm.api().submit("low", 10, scene)["id"];
  const std::string high = farm.api().submit("high", 90, scene)["id"];
  // One single-threaded worker: the tiles are rendered strictly one after another.
  const auto worker = farm.start_worker("solo", 1);

  const json low_done = farm.wait_finished(low, 60s);
  const json high_done = farm.wait_finished(high, 60s);
  ASSERT_EQ(low_done["state"], "completed") << low_done.dump();
  ASSERT_EQ(high_done["state"], "completed") << high_done.dump();
  EXPECT_LT(epoch_ms(high_done["finished_at"]), epoch_ms(low_done["finished_at"]));
  // Not interleaved either: the low job got its first tile only when the high one's were
  // all handed out. A worker may claim its next tile while the last one is still on its
  // way, so the low job may start up to one tile before the high job is recorded finished.
  const std::int64_t high_start = epoch_ms(high_done["started_at"]);
  const std::int64_t high_end = epoch_ms(high_done["finished_at"]);
  const std::int64_t one_tile =
      (high_end - high_start) / high_done["tiles"]["total"].get<int>() + 1;
  EXPECT_GE(epoch_ms(low_done["started_at"]), high_end - 2 * one_tile)
      << "low started at " << low_done["started_at"] << ", high ran from "
      << high_done["started_at"] << " to " << high_done["finished_at"];
}

TEST(FarmSchedulingTest, AWorkerJoiningMidJobGetsTiles) {
  Farm farm("sched-late", 1, {"--worker-threads", "1"});
  const json scene = test::showcase(
      320, 240, 32, 16);  // 300 tiles, ~2 s for one thread: outlasts a worker's start
  const std::string id = farm.api().submit("late join", 50, scene)["id"];
  ASSERT_TRUE(test::eventually([&] { return farm.api().job(id)["tiles"]["done"] >= 5; }, 30s));

  const auto late = farm.start_worker("late", 1);
  ASSERT_TRUE(test::eventually([&] { return farm.worker_named("late").has_value(); }, 20s))
      << "the late worker never registered; see " << (farm.dir() / "late.log");
  ASSERT_NE(farm.api().job(id)["state"], "completed")
      << "the job finished before the late worker joined: make it bigger";

  const json done = farm.wait_finished(id, 60s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  const auto late_info = farm.worker_named("late");
  ASSERT_TRUE(late_info.has_value());
  EXPECT_GT((*late_info)["tiles_rendered"].get<int>(), 0) << late_info->dump();
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
}

TEST(FarmSchedulingTest, AWorkerStoppedWithSigtermDeliversItsTile) {
  // A lease that is lost rather than delivered or released would hold its tile for a
  // minute, far longer than this test waits.
  Farm farm("sched-sigterm", 0, {"--lease-timeout", "60"});
  const json scene = test::showcase(256, 192, 32, 64);  // 12 tiles of a good fraction of a second
  const std::string id = farm.api().submit("sigterm", 50, scene)["id"];
  const int total = farm.api().job(id)["tiles"]["total"];

  auto first = farm.start_worker("first", 1);
  // Stop it once it is well into the job, in the middle of a tile: it has delivered one
  // and has held its current tile for a while, so it is past claiming and rendering it.
  json seen;
  json held;  // the (tile, tiles rendered) it is on, and since when
  auto held_since = std::chrono::steady_clock::now();
  ASSERT_TRUE(test::eventually(
      [&] {
        const auto info = farm.worker_named("first");
        if (!info) return false;
        seen = *info;
        if (seen["state"] != "rendering" || seen["tiles_rendered"].get<int>() < 1) return false;
        const json now_on = {seen["current_tile"], seen["tiles_rendered"]};
        if (now_on != held) {
          held = now_on;
          held_since = std::chrono::steady_clock::now();
        }
        return std::chrono::steady_clock::now() - held_since >= 40ms;
      },
      30s))
      << seen.dump();
  const int rendered_before = seen["tiles_rendered"];
  const auto stopped_at = std::chrono::steady_clock::now();
  first->signal(SIGTERM);
  const auto status = first->wait_for(15s);
  ASSERT_TRUE(status.has_value()) << "the worker did not exit after SIGTERM";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << "status " << *status;
  EXPECT_LT(std::chrono::steady_clock::now() - stopped_at, 10s);

  // It finished and delivered the tile it was rendering, and said goodbye.
  const json after = *farm.worker_named("first");
  EXPECT_GE(after["tiles_rendered"].get<int>(), rendered_before + 1)
      << "the tile in progress at SIGTERM was not delivered; see " << (farm.dir() / "first.log");
  EXPECT_EQ(after["state"], "left");
  EXPECT_LT(farm.api().job(id)["tiles"]["done"].get<int>(), total)
      << "nothing left for a second worker";

  auto second = farm.start_worker("second", 1);
  const json done = farm.wait_finished(id, 40s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  EXPECT_LT(std::chrono::steady_clock::now() - stopped_at, 40s);
  EXPECT_EQ(done["tiles"]["done"], total);
  EXPECT_EQ(done["tiles"]["done"], done["tiles"]["total"]);
  // Every tile delivered exactly once, by one of the two.
  const int by_first = farm.worker_named("first").value()["tiles_rendered"];
  const int by_second = farm.worker_named("second").value()["tiles_rendered"];
  EXPECT_EQ(by_first + by_second, total);
  EXPECT_GT(by_second, 0);
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
}

TEST(FarmSchedulingTest, AnIdleWorkerExitsAtOnceOnSigterm) {
  Farm farm("sched-idle-stop", 0);
  auto idle = farm.start_worker("idle", 1);
  ASSERT_TRUE(test::eventually([&] { return farm.worker_named("idle").has_value(); }, 20s))
      << "the worker never registered; see " << (farm.dir() / "idle.log");
  // Registered, so its first claim is on its way and then parked: there is no job, and a
  // claim waits 10 s for one.
  std::this_thread::sleep_for(300ms);
  const auto stopped_at = std::chrono::steady_clock::now();
  idle->signal(SIGTERM);
  const auto status = idle->wait_for(15s);
  ASSERT_TRUE(status.has_value()) << "the worker did not exit after SIGTERM";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << "status " << *status;
  EXPECT_LT(std::chrono::steady_clock::now() - stopped_at, 3s)
      << "the worker sat out its long poll instead of stopping";
  EXPECT_EQ(farm.worker_named("idle").value()["state"], "left");  // it said goodbye
  EXPECT_EQ(test::read_text(farm.dir() / "idle.log").find("cannot reach"), std::string::npos)
      << "the interrupted claim was reported as an unreachable coordinator";
}

}  // namespace
}  // namespace tessera
