// Fault injection on a real coordinator: each SQLite call (prepare, step, the RELEASE that
// commits, the checkpoint) and each file write (ENOSPC, EIO) and open (EMFILE) of its data
// dir fails in turn, from a random point of a farm run on, for a random number of calls
// (tests/farm/fault_shim.cpp, preloaded). The run goes on through the fault: jobs are
// submitted, rendered, retried when they fail. Then the coordinator is killed and started
// again without faults, and every answer it gave before holds: each job it acknowledged
// is there, with at least the tiles it reported done, a job it reported completed is
// completed with the local render's pixels, and every job then completes bit for bit.
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

// A fault kind, and the range its first fault is drawn from: matching calls after the
// run's first submission. Statements are prepared once and cached, so few prepares come;
// every statement steps, so many steps do.
struct FaultKind {
  std::string name;
  long first_after_min;
  long first_after_max;
  long count_max;
};

// The ranges fit a run's own calls, as TESSERA_FAULT_TALLY counted them in one: 9
// prepares, 121 steps, 46 commits, 1 checkpoint (the large scene's), 197 writes and 8
// opens of the data dir's files.
const std::vector<FaultKind> kinds{
    {"sqlite_prepare", 0, 6, 3},    {"sqlite_step", 5, 100, 6},   {"sqlite_release", 2, 40, 4},
    {"sqlite_checkpoint", 0, 0, 2}, {"write_enospc", 5, 180, 40}, {"write_eio", 5, 180, 6},
    {"open_emfile", 0, 6, 8},
};

// The showcase with a 200,000-triangle grid far below it: a scene of about 5 MB, whose
// one row fills more of the WAL than a checkpoint waits for.
json heavy_scene() {
  json scene = test::showcase(64, 48, 1, 8);
  constexpr int side = 317;
  json positions = json::array();
  json triangles = json::array();
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      positions.push_back({x * 0.013579 - 2.0, -40.123456, y * 0.013579 - 2.0});
  for (int y = 0; y + 1 < side; ++y)
    for (int x = 0; x + 1 < side; ++x) {
      const int corner = y * side + x;
      triangles.push_back({corner, corner + side, corner + 1});
      triangles.push_back({corner + 1, corner + side, corner + side + 1});
    }
  scene["objects"].push_back({{"type", "mesh"},
                              {"material", scene["objects"][0]["material"]},
                              {"positions", std::move(positions)},
                              {"triangles", std::move(triangles)}});
  return scene;
}

// What the coordinator said of a job, all told: it was there, with this many tiles done.
struct Acknowledged {
  int tiles_done = 0;
  bool completed = false;
  bool failed = false;  // once, whatever came after
};

struct Totals {
  int faults = 0;
  int restarts = 0;
  int jobs = 0;
  int tiles_lost = 0;
};

class FaultRun {
 public:
  FaultRun(const fs::path& dir, const FaultKind& kind, long after, long count)
      : dir_(dir), arm_(dir / "arm"), log_(dir / "faults.log") {
    std::vector<std::string> args{"LD_PRELOAD=" + std::string(TESSERA_FAULT_SHIM),
                                  "TESSERA_FAULT=" + kind.name,
                                  "TESSERA_FAULT_AFTER=" + std::to_string(after),
                                  "TESSERA_FAULT_COUNT=" + std::to_string(count),
                                  "TESSERA_FAULT_PATH=" + (dir / "data").string(),
                                  "TESSERA_FAULT_LOG=" + log_.string(),
                                  "TESSERA_FAULT_ARM=" + arm_.string(),
                                  TESSERA_SERVER_BIN};
    const std::vector<std::string> server = coordinator_args();
    args.insert(args.end(), server.begin(), server.end());
    server_ = std::make_unique<test::Process>("/usr/bin/env", args, dir / "server.log");
    port_ = wait_port();
  }

  std::vector<std::string> coordinator_args() const {
    return {"--listen",        "127.0.0.1:0", "--data-dir",           (dir_ / "data").string(),
            "--local-workers", "0",           "--port-file",          (dir_ / "port").string(),
            "--lease-timeout", "2",           "--heartbeat-interval", "0.2",
            "--log-level",     "info"};
  }
  int wait_port() { return test::port_from_file(dir_, dir_ / "server.log"); }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  // From now on the faults count down.
  void arm() const { test::write_text(arm_, "armed\n"); }
  int faults() const {
    std::ifstream in(log_);
    int lines = 0;
    for (std::string line; std::getline(in, line);) ++lines;
    return lines;
  }
  // SIGKILL: nothing flushed on the way out, only what was committed counts.
  void kill_and_restart() {
    server_->signal(SIGKILL);
    server_->wait_for(10s);
    fs::remove(dir_ / "port");
    server_ = std::make_unique<test::Process>(TESSERA_SERVER_BIN, coordinator_args(),
                                              dir_ / "server-restarted.log");
    port_ = wait_port();
  }
  std::unique_ptr<test::Process> start_worker(const std::string& name) const {
    return std::make_unique<test::Process>(
        TESSERA_WORKER_BIN,
        std::vector<std::string>{"--server", url(), "--threads", "2", "--name", name, "--log-level",
                                 "warn"},
        dir_ / (name + ".log"));
  }

 private:
  fs::path dir_;
  fs::path arm_;
  fs::path log_;
  std::unique_ptr<test::Process> server_;
  int port_ = 0;
};

// The job as the coordinator answers it now, or null when it answers otherwise.
json job_status(HttpClient& http, const std::string& id) {
  try {
    const HttpResult reply = http.request("GET", "/v1/jobs/" + id);
    if (reply.status != 200) return nullptr;
    return json::parse(reply.body);
  } catch (const std::exception&) {
    return nullptr;  // no answer: the coordinator is busy or gone
  }
}

bool finished(const json& job) {
  return job.is_object() &&
         (job["state"] == "completed" || job["state"] == "failed" || job["state"] == "canceled");
}

// Follows a job until it finishes (retrying it when it fails, a few times), noting what
// every answer said of it.
void follow(HttpClient& http, const std::string& id, Acknowledged& seen) {
  for (int retries = 0; retries < 4; ++retries) {
    json job;
    test::eventually(
        [&] {
          job = job_status(http, id);
          if (job.is_object()) {
            seen.tiles_done = std::max(seen.tiles_done, job["tiles"]["done"].get<int>());
            seen.completed = seen.completed || job["state"] == "completed";
            seen.failed = seen.failed || job["state"] == "failed";
          }
          return finished(job);
        },
        30s);
    if (!job.is_object() || job["state"] != "failed") return;
    try {
      http.request("POST", "/v1/jobs/" + id + "/retry", "");
    } catch (const std::exception&) {
    }
  }
}

TEST(FarmStoreFaultsTest, EveryAnswerHoldsAfterEachInjectedFaultAndARestart) {
  const unsigned seed = std::getenv("TESSERA_FAULT_SEED")
                            ? static_cast<unsigned>(std::atol(std::getenv("TESSERA_FAULT_SEED")))
                            : std::random_device{}();
  std::mt19937 random(seed);
  std::cout << "TESSERA_FAULT_SEED=" << seed << " reproduces this run\n";
  // Each run submits the heavy scene first, then three light ones: 48 tiles each.
  const std::vector<json> scenes{heavy_scene(), test::showcase(64, 48, 1, 8)};
  const std::vector<Image> references{test::render_image(scenes[0], 2),
                                      test::render_image(scenes[1], 2)};
  const fs::path top = test::fresh_dir("store-faults");
  Totals totals;
  int run_number = 0;
  for (const FaultKind& kind : kinds) {
    int faults_of_kind = 0;
    for (int round = 0; round < 2; ++round) {
      const long after =
          std::uniform_int_distribution<long>(kind.first_after_min, kind.first_after_max)(random);
      const long count = std::uniform_int_distribution<long>(1, kind.count_max)(random);
      SCOPED_TRACE(kind.name + " after " + std::to_string(after) + " calls, " +
                   std::to_string(count) + " times; seed " + std::to_string(seed));
      const fs::path dir = top / ("run-" + std::to_string(++run_number));
      fs::create_directories(dir);
      FaultRun run(dir, kind, after, count);
      std::map<std::string, Acknowledged> acknowledged;
      std::map<std::string, int> scene_of;
      {
        HttpClient http(run.url(), 10s);
        auto worker = run.start_worker("w");
        run.arm();
        for (int j = 0; j < 4; ++j) {
          HttpResult reply;
          try {
            reply = http.request(
                "POST", "/v1/jobs",
                json{{"name", "job " + std::to_string(j)}, {"scene", scenes[j == 0 ? 0 : 1]}}
                    .dump());
          } catch (const std::exception& e) {
            ADD_FAILURE() << "the coordinator did not answer a submission: " << e.what();
            continue;
          }
          if (reply.status != 201) {
            // Refused, and said so: nothing was promised.
            EXPECT_TRUE(reply.status == 507 || reply.status == 503) << reply.status << reply.body;
            continue;
          }
          const std::string id = json::parse(reply.body)["id"];
          scene_of[id] = j == 0 ? 0 : 1;
          follow(http, id, acknowledged[id]);
        }
      }
      // A shortage of descriptors passes: it is waited out, and fails no job.
      if (kind.name == "open_emfile")
        for (const auto& [id, seen] : acknowledged) {
          EXPECT_FALSE(seen.failed) << "job " << id;
        }
      const int faults = run.faults();
      faults_of_kind += faults;
      totals.faults += faults;
      run.kill_and_restart();
      ++totals.restarts;

      HttpClient http(run.url(), 10s);
      auto worker = run.start_worker("w-after");
      for (auto& [id, seen] : acknowledged) {
        ++totals.jobs;
        const json job = job_status(http, id);
        ASSERT_TRUE(job.is_object()) << "job " << id << " was acknowledged, then lost";
        const int done = job["tiles"]["done"];
        EXPECT_GE(done, seen.tiles_done) << "job " << id << " lost tiles it reported done";
        totals.tiles_lost += std::max(0, seen.tiles_done - done);
        if (seen.completed) {
          EXPECT_EQ(job["state"], "completed") << job.dump();
        }
        Acknowledged after;
        follow(http, id, after);
        const json end = job_status(http, id);
        ASSERT_TRUE(end.is_object());
        ASSERT_EQ(end["state"], "completed") << end.dump();
        const HttpResult image = http.request("GET", "/v1/jobs/" + id + "/image?format=exr");
        ASSERT_EQ(image.status, 200);
        const fs::path file = dir / (id + ".exr");
        test::write_text(file, image.body);
        EXPECT_TRUE(test::same_pixels(read_image(file), references[scene_of[id]])) << "job " << id;
      }
    }
    EXPECT_GT(faults_of_kind, 0) << kind.name << ": no fault was injected in either run";
  }
  std::cout << "faults injected: " << totals.faults << ", restarts: " << totals.restarts
            << ", jobs checked: " << totals.jobs << ", tiles lost: " << totals.tiles_lost << "\n";
  EXPECT_EQ(totals.tiles_lost, 0);
  EXPECT_GT(totals.jobs, 0);
}

}  // namespace
}  // namespace tessera
