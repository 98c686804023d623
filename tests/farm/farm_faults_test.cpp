// Faults with real processes and real signals: a worker killed in the middle of a tile, a
// coordinator killed in the middle of a job and started again, a worker frozen until its
// lease was given away. In every case the job completes with the image of a render
// without the fault, and no tile is taken from two workers.
#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

// Short leases, so that a lost worker's tiles come back within a test's patience.
const std::vector<std::string> quick_leases{"--lease-timeout", "1", "--heartbeat-interval", "0.2"};

// Waits until the worker of that name is rendering, having delivered `delivered` tiles.
::testing::AssertionResult rendering_after(Farm& farm, const std::string& name, int delivered) {
  const bool seen = test::eventually(
      [&] {
        const auto info = farm.worker_named(name);
        return info && (*info)["state"] == "rendering" &&
               (*info)["tiles_rendered"].get<int>() >= delivered;
      },
      30s);
  if (seen) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << name << " never got to rendering after " << delivered << " tiles";
}

// Waits until the job has finished, and returns it as then answered.
json farm_wait(test::JsonApi& api, const std::string& id) {
  json job;
  test::eventually(
      [&] {
        job = api.job(id);
        return job["state"] == "completed" || job["state"] == "failed" ||
               job["state"] == "canceled";
      },
      120s);
  return job;
}

// Whether a second connection gets the database's write lock within a second: none does
// while the coordinator holds a transaction open.
bool another_writer_can_write(const fs::path& database) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(database.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    sqlite3_close(db);
    return false;
  }
  sqlite3_busy_timeout(db, 1000);
  const bool locked = sqlite3_exec(db, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr) == SQLITE_OK;
  if (locked) sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  return locked;
}

TEST(FarmFaultsTest, AWorkerKilledMidTileLosesNothing) {
  Farm farm("fault-kill-worker", 0, quick_leases);
  const json scene = test::showcase(256, 192, 32, 32);  // 48 tiles, ~1.2 s for one thread
  const std::string id = farm.api().submit("kill", 50, scene)["id"];
  auto doomed = farm.start_worker("doomed", 1);
  ASSERT_TRUE(rendering_after(farm, "doomed", 2));
  doomed->signal(SIGKILL);
  ASSERT_TRUE(doomed->wait_for(10s).has_value());
  const int done_at_kill = farm.api().job(id)["tiles"]["done"];
  ASSERT_LT(done_at_kill, 48) << "the job finished before the kill: make it bigger";

  auto rescuer = farm.start_worker("rescuer", 1);
  const json done = farm.wait_finished(id, 60s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
  // The killed worker's tiles came back through expiry, not through anything it said.
  EXPECT_NE(test::read_text(farm.dir() / "server.log").find("expired without a heartbeat"),
            std::string::npos);
  const int by_doomed = farm.worker_named("doomed").value()["tiles_rendered"];
  const int by_rescuer = farm.worker_named("rescuer").value()["tiles_rendered"];
  EXPECT_EQ(by_doomed + by_rescuer, 48);
  EXPECT_GE(by_doomed, done_at_kill == 0 ? 0 : 1);
}

TEST(FarmFaultsTest, ALongTileOnALiveWorkerIsNeverTakenAway) {
  // Each tile takes several lease timeouts to render; only the heartbeats keep it.
  Farm farm("fault-long-tile", 0, quick_leases);
  const json scene = test::showcase(128, 64, 768, 64);  // 2 tiles of 64x64 at 768 spp
  const std::string id = farm.api().submit("long", 50, scene)["id"];
  auto worker = farm.start_worker("steady", 1);
  const json done = farm.wait_finished(id, 120s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  const double seconds = done["elapsed_s"];
  ASSERT_GT(seconds, 2.0) << "the tiles were too quick to outlast a lease: make them slower";
  EXPECT_EQ(test::read_text(farm.dir() / "server.log").find("expired"), std::string::npos)
      << "a lease expired while its worker was heartbeating";
  EXPECT_EQ(farm.worker_named("steady").value()["tiles_rendered"], 2);
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
}

TEST(FarmFaultsTest, AFrozenWorkerThatComesBackLateIsFencedOut) {
  Farm farm("fault-fence", 0, quick_leases);
  const json scene = test::showcase(256, 192, 16, 32);  // 48 tiles
  const std::string id = farm.api().submit("fence", 50, scene)["id"];
  auto frozen = farm.start_worker("frozen", 1);
  ASSERT_TRUE(rendering_after(farm, "frozen", 1));
  frozen->signal(SIGSTOP);  // mid-lease: no heartbeats, no uploads
  ASSERT_TRUE(
      test::eventually([&] { return farm.worker_named("frozen").value()["state"] == "idle"; }, 20s))
      << "the frozen worker's lease did not expire";
  auto rescuer = farm.start_worker("rescuer", 1);
  ASSERT_TRUE(test::eventually(
      [&] {
        return farm.worker_named("rescuer").value_or(
                   json{{"tiles_rendered", 0}})["tiles_rendered"] >= 2;
      },
      30s));
  frozen->signal(SIGCONT);

  const json done = farm.wait_finished(id, 90s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
  // The frozen worker was told its late tiles were refused, dropped them and went on.
  ASSERT_TRUE(test::eventually(
      [&] {
        return test::read_text(farm.dir() / "frozen.log").find("refused") != std::string::npos;
      },
      10s))
      << "the late result was not refused; see " << (farm.dir() / "frozen.log");
  EXPECT_TRUE(frozen->wait_for(0ms) == std::nullopt)
      << "the frozen worker died instead of carrying on";
  EXPECT_EQ(test::read_text(farm.dir() / "server.log").find("duplicate result"), std::string::npos);
  const int by_frozen = farm.worker_named("frozen").value()["tiles_rendered"];
  const int by_rescuer = farm.worker_named("rescuer").value()["tiles_rendered"];
  EXPECT_EQ(by_frozen + by_rescuer, 48) << "a tile was accepted from two workers, or from none";
}

TEST(FarmFaultsTest, ACoordinatorKilledMidJobResumesWithoutRenderingDeliveredTilesAgain) {
  const fs::path dir = test::fresh_dir("fault-kill-server");
  const json scene = test::showcase(320, 240, 24, 32);  // 80 tiles, ~1.4 s for one thread

  auto [server, port] = test::start_coordinator(dir, "127.0.0.1:0", "first.log");
  const std::string url = "http://127.0.0.1:" + std::to_string(port);
  test::JsonApi api(url);
  const std::string id = api.submit("resume", 50, scene)["id"];
  const std::string canceled = api.submit("canceled", 10, scene)["id"];
  ASSERT_EQ(api.cancel(canceled)["state"], "canceled");
  auto worker = std::make_unique<test::Process>(
      TESSERA_WORKER_BIN,
      std::vector<std::string>{"--server", url, "--threads", "1", "--name", "survivor",
                               "--log-level", "info"},
      dir / "survivor.log");
  ASSERT_TRUE(test::eventually([&] { return api.job(id)["tiles"]["done"].get<int>() >= 10; }, 60s));
  server->signal(SIGKILL);
  ASSERT_TRUE(server->wait_for(10s).has_value());
  // Read from the store, as the next coordinator will: every tile acknowledged is there.
  const int acknowledged = [&] {
    auto [probe, probe_port] = test::start_coordinator(dir, "127.0.0.1:0", "probe.log");
    test::JsonApi probe_api("http://127.0.0.1:" + std::to_string(probe_port));
    const int done = probe_api.job(id)["tiles"]["done"];
    probe->signal(SIGKILL);
    probe->wait_for(10s);
    return done;
  }();
  ASSERT_GE(acknowledged, 10);
  ASSERT_LT(acknowledged, 80) << "the job finished before the kill: make it bigger";

  // The same address again: the worker, which kept retrying, finds it by itself.
  auto [again, again_port] =
      test::start_coordinator(dir, "127.0.0.1:" + std::to_string(port), "second.log");
  ASSERT_EQ(again_port, port);
  const json done = [&] {
    json job;
    test::eventually(
        [&] {
          job = api.job(id);
          return job["state"] == "completed";
        },
        90s);
    return job;
  }();
  ASSERT_EQ(done["state"], "completed") << done.dump();
  EXPECT_EQ(api.job(canceled)["state"], "canceled");
  const fs::path exr = dir / "resumed.exr";
  test::write_text(exr, api.image(id, "exr", false));
  EXPECT_TRUE(test::same_pixels(read_image(exr), test::render_image(scene, 2)));

  // No tile was rendered twice: the one worker rendered exactly the job's 80 tiles, the
  // ones done before the crash included, and none of the canceled job's.
  worker->signal(SIGTERM);
  ASSERT_TRUE(worker->wait_for(20s).has_value());
  EXPECT_EQ(test::tiles_rendered_by(dir / "survivor.log"), 80) << "see " << (dir / "survivor.log");
  again->signal(SIGTERM);
  again->wait_for(20s);
}

// Sets an environment variable for the processes started while it lives.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() { ::unsetenv(name_); }

 private:
  const char* name_;
};

// The tile handed out first (centre-first): the one every fault below is put on.
int first_tile_of(const json& scene) {
  const int tile = scene["render"]["tile_size"];
  const int columns = (scene["image"]["width"].get<int>() + tile - 1) / tile;
  const int rows = (scene["image"]["height"].get<int>() + tile - 1) / tile;
  return rows / 2 * columns + columns / 2;
}

TEST(FarmFaultsTest, ATileThatCrashesItsWorkerFailsTheJobAfterThreeTries) {
  const json scene = test::showcase(256, 192, 4, 32);  // 48 tiles
  const int poison = first_tile_of(scene);
  // Local workers inherit the fault from the coordinator's environment; each one that
  // dies is replaced, so the tile is tried again and again.
  const ScopedEnv fault("TESSERA_FAULT_INJECTION", "crash:" + std::to_string(poison));
  std::vector<std::string> args = quick_leases;
  args.insert(args.end(), {"--worker-threads", "1"});
  Farm farm("fault-crash-tile", 2, args);
  const std::string id = farm.api().submit("poison", 50, scene)["id"];
  const json done = farm.wait_finished(id, 90s);
  ASSERT_EQ(done["state"], "failed") << done.dump();
  const std::string error = done["error"];
  EXPECT_NE(error.find("tile " + std::to_string(poison) + " "), std::string::npos) << error;
  EXPECT_NE(error.find("failed 3 times"), std::string::npos) << error;
  EXPECT_NE(error.find("stopped responding"), std::string::npos) << error;
  // The farm is not stuck on it: the next job completes on the same workers.
  json healthy = scene;
  healthy["image"]["width"] = 64;  // one tile that is not the poisoned index
  healthy["image"]["height"] = 32;
  const std::string next = farm.api().submit("after", 50, healthy)["id"];
  EXPECT_EQ(farm.wait_finished(next, 60s)["state"], "completed");
}

TEST(FarmFaultsTest, ATileWhoseWorkerReportsAnErrorIsRetriedElsewhereThenFailsTheJob) {
  const json scene = test::showcase(256, 192, 4, 32);
  const int poison = first_tile_of(scene);
  Farm farm("fault-error-tile", 0);
  std::vector<std::unique_ptr<test::Process>> workers;
  {
    const ScopedEnv fault("TESSERA_FAULT_INJECTION", "error:" + std::to_string(poison));
    for (const char* name : {"one", "two", "three"}) workers.push_back(farm.start_worker(name, 1));
  }
  ASSERT_TRUE(test::eventually([&] { return farm.api().workers()["workers"].size() == 3; }, 20s));
  const std::string id = farm.api().submit("reported", 50, scene)["id"];
  const json done = farm.wait_finished(id, 60s);
  ASSERT_EQ(done["state"], "failed") << done.dump();
  // 8 columns of 32-pixel tiles.
  const std::string at =
      "(" + std::to_string(poison % 8 * 32) + ", " + std::to_string(poison / 8 * 32) + ")";
  EXPECT_EQ(done["error"], "tile " + std::to_string(poison) + " at " + at +
                               " failed 3 times; the last error: fault injection: error on tile " +
                               std::to_string(poison));
  // Reporting is not crashing: every worker is still there, and tried the tile.
  int reporters = 0;
  for (const char* name : {"one", "two", "three"}) {
    EXPECT_FALSE(workers[static_cast<std::size_t>(reporters)]->wait_for(0ms).has_value())
        << name << " died";
    reporters += test::read_text(farm.dir() / (std::string(name) + ".log"))
                     .find("failed: fault injection") != std::string::npos;
  }
  EXPECT_GE(reporters, 2) << "the tile was not retried on another worker";
}

TEST(FarmFaultsTest, AFullDiskFailsTheJobWithAClearErrorAndTheServerKeepsServing) {
  const fs::path dir = test::fresh_dir("fault-disk-full");
  const fs::path data = dir / "data";
  // A 2 MiB file system for the data dir.
  const test::SmallDisk disk(data, "2m");
  if (!disk.mounted())
    GTEST_SKIP() << "needs root to mount a small tmpfs for the data dir (CI runs as root); see "
                 << (dir / "mount.log");

  auto server = std::make_unique<test::Process>(
      TESSERA_SERVER_BIN,
      std::vector<std::string>{"--listen", "127.0.0.1:0", "--data-dir", data.string(),
                               "--local-workers", "1", "--worker-threads", "1", "--port-file",
                               (dir / "port").string(), "--log-level", "info"},
      dir / "server.log");
  ASSERT_TRUE(test::eventually([&] { return fs::exists(dir / "port"); }, 20s))
      << test::read_text(dir / "server.log");
  int port = 0;
  std::ifstream(dir / "port") >> port;
  const std::string url = "http://127.0.0.1:" + std::to_string(port);
  test::JsonApi api(url);
  // 256 tiles of 12 KiB of pixels: 3 MiB, more than the disk holds.
  const std::string id =
      api.submit("too big for the disk", 50, test::showcase(512, 512, 1, 32))["id"];
  json job;
  ASSERT_TRUE(test::eventually(
      [&] {
        job = api.job(id);
        return job["state"] != "queued" && job["state"] != "running";
      },
      60s))
      << job.dump();
  EXPECT_EQ(job["state"], "failed") << job.dump();
  const std::string error = job["error"].is_string() ? job["error"].get<std::string>() : "";
  EXPECT_NE(error.find("cannot store"), std::string::npos) << error;
  EXPECT_NE(error.find("full"), std::string::npos) << error;
  // Named within the data dir: the server's own paths are none of a client's business.
  EXPECT_EQ(error.find(data.string()), std::string::npos) << error;
  // Which write meets the full disk first depends on timing: the pixels, or the store's log.
  EXPECT_TRUE(error.find("pixels/" + id + ".f32") != std::string::npos ||
              error.find("cannot store a change") != std::string::npos)
      << error;

  // Still serving: status, lists, health; a new job gets an answer, stored or refused clearly.
  EXPECT_FALSE(server->wait_for(0ms).has_value()) << "the coordinator died";
  HttpClient http(url, 10s);
  EXPECT_EQ(http.request("GET", "/healthz").status, 200);
  EXPECT_EQ(http.request("GET", "/v1/jobs").status, 200);
  const HttpResult again = http.request(
      "POST", "/v1/jobs", json{{"name", "small"}, {"scene", test::showcase(16, 16, 1, 16)}}.dump());
  EXPECT_TRUE(again.status == 201 || again.status == 507) << again.status << " " << again.body;
  if (again.status == 507) {
    EXPECT_NE(again.body.find("storage_failed"), std::string::npos) << again.body;
  }
  server->signal(SIGTERM);
  const auto status = server->wait_for(30s);
  ASSERT_TRUE(status.has_value());
}

// The reproduction: a data dir on a 20 MiB tmpfs fills while a job writes its
// pixels; once the space is back, a retry of that job and a new job both complete, and a
// restart finds both as they were answered. Before, the rollback of the failed change
// left its transaction open: nothing was committed again, yet every answer said it was.
TEST(FarmFaultsTest, AFullDiskThenSpaceBackThenASubmitAndARestartKeepTheJob) {
  const fs::path dir = test::fresh_dir("fault-disk-refill");
  const fs::path data = dir / "data";
  const test::SmallDisk disk(data, "20m");
  if (!disk.mounted())
    GTEST_SKIP() << "needs root to mount a small tmpfs for the data dir (CI runs as root); see "
                 << (dir / "mount.log");
  const auto start = [&](const std::string& log) {
    fs::remove(dir / "port");
    auto server = std::make_unique<test::Process>(
        TESSERA_SERVER_BIN,
        std::vector<std::string>{"--listen", "127.0.0.1:0", "--data-dir", data.string(),
                                 "--local-workers", "1", "--worker-threads", "2", "--port-file",
                                 (dir / "port").string(), "--log-level", "info"},
        dir / log);
    const int port = test::port_from_file(dir, dir / log);
    return std::make_pair(std::move(server), "http://127.0.0.1:" + std::to_string(port));
  };
  auto [server, url] = start("server.log");
  test::JsonApi api(url);
  // All but 1 MiB taken; the job's pixels need 3.5 MiB.
  const fs::space_info space = fs::space(data);
  {
    std::ofstream filler(data / "filler", std::ios::binary);
    const std::string block(1 << 20, 'x');
    for (auto left = space.available; left > (2u << 20); left -= block.size())
      filler.write(block.data(), static_cast<std::streamsize>(block.size()));
  }
  const json scene = test::showcase(640, 480, 1, 32);
  const std::string failed = api.submit("fills the disk", 50, scene)["id"];
  const json first = farm_wait(api, failed);
  ASSERT_EQ(first["state"], "failed") << first.dump();
  EXPECT_NE(first["error"].get<std::string>().find("the disk is full"), std::string::npos)
      << first.dump();

  fs::remove(data / "filler");
  EXPECT_EQ(api.retry(failed)["state"], "running");
  const std::string added = api.submit("after the space came back", 50, scene)["id"];
  EXPECT_EQ(farm_wait(api, failed)["state"], "completed");
  EXPECT_EQ(farm_wait(api, added)["state"], "completed");
  const Image reference = test::render_image(scene, 2);
  for (const std::string& id : {failed, added}) {
    test::write_text(dir / (id + ".exr"), api.image(id, "exr", false));
    EXPECT_TRUE(test::same_pixels(read_image(dir / (id + ".exr")), reference)) << id;
  }
  // The idle coordinator holds no write transaction: another writer gets the lock at once.
  EXPECT_TRUE(another_writer_can_write(data / "tessera.db"));

  server->signal(SIGTERM);
  ASSERT_TRUE(server->wait_for(30s).has_value());
  auto [again, again_url] = start("server-again.log");
  test::JsonApi after(again_url);
  for (const std::string& id : {failed, added}) {
    const json job = after.job(id);
    EXPECT_EQ(job["state"], "completed") << job.dump();
    EXPECT_EQ(job["tiles"]["done"], job["tiles"]["total"]) << job.dump();
    test::write_text(dir / (id + "-again.exr"), after.image(id, "exr", false));
    EXPECT_TRUE(test::same_pixels(read_image(dir / (id + "-again.exr")), reference)) << id;
  }
  again->signal(SIGTERM);
  EXPECT_TRUE(again->wait_for(30s).has_value());
}

// A coordinator that cannot start on a full disk says why in the words a person acts on,
// both for a new data dir and for one whose database is already there.
TEST(FarmFaultsTest, AFullDiskAtStartUpIsNamedAsSuch) {
  const fs::path dir = test::fresh_dir("fault-disk-start");
  const fs::path disk_dir = dir / "disk";
  const test::SmallDisk disk(disk_dir, "1m");
  if (!disk.mounted())
    GTEST_SKIP() << "needs root to mount a small tmpfs for the data dir (CI runs as root); see "
                 << (dir / "mount.log");
  const auto start_and_fail = [&](const fs::path& data, const std::string& log) {
    test::Process server(TESSERA_SERVER_BIN,
                         {"--listen", "127.0.0.1:0", "--data-dir", data.string(), "--local-workers",
                          "0", "--log-level", "info"},
                         dir / log);
    const auto status = server.wait_for(20s);
    EXPECT_TRUE(status && WIFEXITED(*status) && WEXITSTATUS(*status) != 0)
        << "started on a full disk";
    return test::read_text(dir / log);
  };
  const auto fill = [&] {
    std::ofstream filler(disk_dir / "filler", std::ios::binary | std::ios::app);
    const std::string block(4096, 'x');
    while (filler.write(block.data(), static_cast<std::streamsize>(block.size())) &&
           filler.flush()) {
    }
  };
  // A database made while there was room, then the disk filled: its WAL cannot be made.
  {
    test::Process server(TESSERA_SERVER_BIN,
                         {"--listen", "127.0.0.1:0", "--data-dir", (disk_dir / "kept").string(),
                          "--local-workers", "0", "--port-file", (dir / "port").string()},
                         dir / "first.log");
    ASSERT_TRUE(test::eventually([&] { return fs::exists(dir / "port"); }, 20s));
    server.signal(SIGTERM);
    ASSERT_TRUE(server.wait_for(20s).has_value());
  }
  fill();
  const std::string fresh = start_and_fail(disk_dir / "fresh", "fresh.log");
  EXPECT_NE(fresh.find("the disk is full"), std::string::npos) << fresh;
  const std::string kept = start_and_fail(disk_dir / "kept", "kept.log");
  EXPECT_NE(kept.find("the disk is full"), std::string::npos) << kept;
  EXPECT_EQ(kept.find("disk I/O error\n"), std::string::npos) << kept;
}

TEST(FarmFaultsTest, AWorkerThatKeepsFailingOnAJobIsKeptOffIt) {
  const json scene = test::showcase(256, 192, 4, 32);  // 48 tiles
  Farm farm("fault-kept-off", 0);
  std::unique_ptr<test::Process> flaky;
  {
    // It fails on three tiles; after two failures it gets no more of this job's tiles.
    const ScopedEnv fault("TESSERA_FAULT_INJECTION",
                          "error:" + std::to_string(first_tile_of(scene)) + ",0,47");
    flaky = farm.start_worker("flaky", 1);
  }
  auto sound = farm.start_worker("sound", 1);
  ASSERT_TRUE(test::eventually([&] { return farm.api().workers()["workers"].size() == 2; }, 20s));
  const std::string id = farm.api().submit("kept off", 50, scene)["id"];
  const json done = farm.wait_finished(id, 60s);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
  // Whatever it got before, it failed at most twice: then the sound worker took the rest.
  const std::string log = test::read_text(farm.dir() / "flaky.log");
  int failures = 0;
  for (std::size_t at = log.find("failed: fault injection"); at != std::string::npos;
       at = log.find("failed: fault injection", at + 1))
    ++failures;
  EXPECT_LE(failures, 2) << log;
  EXPECT_EQ(farm.worker_named("flaky").value()["tiles_rendered"].get<int>() +
                farm.worker_named("sound").value()["tiles_rendered"].get<int>(),
            48);
}

}  // namespace
}  // namespace tessera
