// GET /readyz on a real tessera-server: 200 as soon as it answers at all (the database is
// open and reconciled before it listens), 503 from the moment SIGTERM begins the shutdown
// while /healthz still answers 200, so that a Kubernetes Service stops routing to a
// draining coordinator without its liveness probe killing it. And the container image's
// health check, deploy/docker/healthcheck.sh, against the same server.
#include <sys/wait.h>
#include <csignal>

#include <gtest/gtest.h>

#include "common/net/http_client.hpp"
#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

// A tessera-server of its own rather than test::Farm: these tests see it exit, and Farm
// would then wait for it again when it goes.
class Coordinator {
 public:
  Coordinator(const std::string& name, int local_workers) : dir_(test::fresh_dir(name)) {
    process_ = std::make_unique<test::Process>(
        TESSERA_SERVER_BIN,
        std::vector<std::string>{"--listen", "127.0.0.1:0", "--data-dir", (dir_ / "data").string(),
                                 "--local-workers", std::to_string(local_workers), "--port-file",
                                 (dir_ / "port").string(), "--log-level", "warn"},
        dir_ / "server.log");
    if (!test::eventually([&] { return fs::exists(dir_ / "port"); }, 20s))
      throw std::runtime_error("server did not start; see " + (dir_ / "server.log").string());
    std::ifstream(dir_ / "port") >> port_;
  }

  test::Process& process() { return *process_; }
  const fs::path& dir() const { return dir_; }
  int port() const { return port_; }

  // One request on its own connection; status 0 when nothing answered.
  HttpResult get(const std::string& path) const {
    try {
      HttpClient http("http://127.0.0.1:" + std::to_string(port_), 5s);
      return http.request("GET", path);
    } catch (const HttpError&) {
      return {};
    }
  }

  // The exit status of `bash deploy/docker/healthcheck.sh 127.0.0.1:PORT`.
  int healthcheck() const {
    test::Process check("/bin/bash",
                        {(fs::path(TESSERA_SOURCE_DIR) / "deploy/docker/healthcheck.sh").string(),
                         "127.0.0.1:" + std::to_string(port_)},
                        dir_ / "healthcheck.log");
    const auto status = check.wait_for(10s);
    return status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1;
  }

  // SIGTERM, then its exit status (nothing if it has not exited within `limit`).
  std::optional<int> stop(std::chrono::milliseconds limit = 20s) {
    process_->signal(SIGTERM);
    return process_->wait_for(limit);
  }

 private:
  fs::path dir_;
  int port_ = 0;
  std::unique_ptr<test::Process> process_;
};

TEST(FarmReadinessTest, ReadyWhileServingAndNotOnceShutdownHasBegun) {
  Coordinator coordinator("readyz", 1);
  // The first answer already says ready: nothing is served before start-up is over.
  const HttpResult ready = coordinator.get("/readyz");
  EXPECT_EQ(ready.status, 200) << ready.body;
  EXPECT_EQ(nlohmann::json::parse(ready.body)["status"], "ready");

  // The coordinator's shutdown waits for its local workers before it stops serving. With
  // the worker frozen, that wait lasts until the test lets it go: the draining server can
  // be asked as long as needed, without a render to time.
  // Frozen only once it has registered: by then it has blocked SIGTERM for its signal
  // thread. Before that, the coordinator's SIGTERM would kill it even while stopped.
  ASSERT_TRUE(test::eventually(
      [&] {
        const HttpResult listed = coordinator.get("/v1/workers");
        return listed.status == 200 && !nlohmann::json::parse(listed.body)["workers"].empty();
      },
      20s));
  const std::vector<pid_t> workers = test::children_of(coordinator.process().pid());
  ASSERT_EQ(workers.size(), 1u);
  ::kill(workers[0], SIGSTOP);
  coordinator.process().signal(SIGTERM);
  HttpResult draining;
  EXPECT_TRUE(
      test::eventually([&] { return (draining = coordinator.get("/readyz")).status == 503; }, 10s))
      << "GET /readyz answered " << draining.status << " after SIGTERM";
  EXPECT_EQ(nlohmann::json::parse(draining.body.empty() ? "{}" : draining.body)["error"]["code"],
            "shutting_down");
  EXPECT_EQ(coordinator.get("/healthz").status, 200) << "a draining coordinator is still alive";
  EXPECT_EQ(coordinator.get("/readyz").status, 503) << "readiness never comes back during shutdown";

  ::kill(workers[0], SIGCONT);  // it takes the SIGTERM it was sent, and leaves
  const auto status = coordinator.process().wait_for(20s);
  ASSERT_TRUE(status.has_value()) << "the coordinator did not stop";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0);
}

TEST(FarmReadinessTest, TheImagesHealthCheckAsksHealthz) {
  Coordinator coordinator("healthcheck", 0);
  EXPECT_EQ(coordinator.healthcheck(), 0) << test::read_text(coordinator.dir() / "healthcheck.log");
  ASSERT_TRUE(coordinator.stop().has_value());
  EXPECT_EQ(coordinator.healthcheck(), 1) << "a stopped coordinator must be unhealthy";
}

}  // namespace
}  // namespace tessera
