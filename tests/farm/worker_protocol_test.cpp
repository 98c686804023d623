// A tessera-worker meeting a coordinator of another build: it must stop at registration,
// saying which protocol each side speaks, rather than render tiles whose results would be
// refused. The coordinator here is a real HTTP server answering as other builds would; the
// worker is the real program.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <sys/wait.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio/io_context.hpp>
#include <nlohmann/json.hpp>

#include "common/protocol/limits.hpp"
#include "server/http/http_server.hpp"
#include "server/http/router.hpp"
#include "tests/farm/process.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

// A coordinator that answers every registration with `reply` and counts claims: a worker
// that went on past registration would claim.
class OtherCoordinator {
 public:
  // The first `proxy_failures` registrations get a proxy's 502 page instead of `reply`.
  explicit OtherCoordinator(json reply, int proxy_failures = 0) : proxy_failures_(proxy_failures) {
    router_.add("POST", "/v1/workers", [this, reply](HttpRequest&&, Respond respond) {
      if (registrations_++ < proxy_failures_)
        return respond(HttpResponse{502, "text/html", "<html>502 Bad Gateway</html>", {}});
      respond(json_response(201, reply));
    });
    router_.add("POST", "/v1/workers/{id}/claim", [this](HttpRequest&& request, Respond respond) {
      {
        std::lock_guard lock(mutex_);
        const auto secret = request.headers.find("x-tessera-worker-secret");
        claim_secret_ = secret == request.headers.end() ? "" : secret->second;
      }
      ++claims_;
      respond(HttpResponse{204, "", "", {}});
    });
    router_.add("DELETE", "/v1/workers/{id}", [](HttpRequest&&, Respond respond) {
      respond(HttpResponse{204, "", "", {}});
    });
    HttpServerOptions options;
    options.address = "127.0.0.1";
    options.port = 0;
    server_ = std::make_unique<HttpServer>(io_, router_, options);
    thread_ = std::thread([this] { io_.run(); });
  }
  ~OtherCoordinator() {
    server_->stop();
    thread_.join();
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(server_->port()); }
  int claims() const { return claims_; }
  // The worker secret the last claim sent.
  std::string claim_secret() const {
    std::lock_guard lock(mutex_);
    return claim_secret_;
  }

 private:
  boost::asio::io_context io_;
  Router router_;
  std::unique_ptr<HttpServer> server_;
  std::thread thread_;
  std::atomic<int> claims_{0};
  std::atomic<int> registrations_{0};
  int proxy_failures_;
  mutable std::mutex mutex_;
  std::string claim_secret_;
};

struct Outcome {
  std::optional<int> status;
  std::string log;
};

Outcome run_worker_against(const json& reply, const std::string& name) {
  OtherCoordinator coordinator(reply);
  const fs::path log =
      fs::temp_directory_path() /
      ("tessera-worker-protocol-" + std::to_string(::getpid()) + "-" + name + ".log");
  fs::remove(log);
  Outcome outcome;
  {
    test::Process worker(TESSERA_WORKER_BIN,
                         {"--server", coordinator.url(), "--threads", "1", "--name", name}, log);
    outcome.status = worker.wait_for(20s);
    if (!outcome.status) worker.signal(SIGKILL);
  }
  EXPECT_EQ(coordinator.claims(), 0) << name << " went on to claim tiles";
  std::ifstream in(log);
  outcome.log.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return outcome;
}

void stops_with_status_1(const Outcome& outcome) {
  ASSERT_TRUE(outcome.status) << "the worker did not stop: " << outcome.log;
  ASSERT_TRUE(WIFEXITED(*outcome.status)) << outcome.log;
  EXPECT_EQ(WEXITSTATUS(*outcome.status), 1) << outcome.log;
}

TEST(WorkerProtocolTest, AWorkerStopsAtACoordinatorThatStatesNoProtocol) {
  // What builds before protocol 2 answered.
  const Outcome outcome = run_worker_against(
      {{"id", "w-1"}, {"heartbeat_interval_s", 5}, {"lease_timeout_s", 30}}, "v1");
  stops_with_status_1(outcome);
  EXPECT_NE(outcome.log.find("speaks worker protocol 1 (it states none), this worker " +
                             std::to_string(kWorkerProtocolVersion)),
            std::string::npos)
      << outcome.log;
}

TEST(WorkerProtocolTest, AWorkerStopsAtACoordinatorOfALaterProtocol) {
  json reply = {{"id", "w-1"}, {"protocol", kWorkerProtocolVersion + 1}};
  reply["limits"] = protocol::to_json(ProtocolLimits{});
  const Outcome outcome = run_worker_against(reply, "v3");
  stops_with_status_1(outcome);
  EXPECT_NE(
      outcome.log.find("speaks worker protocol " + std::to_string(kWorkerProtocolVersion + 1)),
      std::string::npos)
      << outcome.log;
}

TEST(WorkerProtocolTest, AWorkerStopsAtACoordinatorWhoseLimitsItCannotKeepTo) {
  json limits = protocol::to_json(ProtocolLimits{});
  limits["max_result_tiles"] = 0;
  const Outcome outcome = run_worker_against({{"id", "w-1"},
                                              {"secret", "s"},
                                              {"heartbeat_interval_s", 5},
                                              {"lease_timeout_s", 30},
                                              {"protocol", kWorkerProtocolVersion},
                                              {"limits", limits}},
                                             "zero");
  stops_with_status_1(outcome);
  EXPECT_NE(outcome.log.find("/limits/max_result_tiles: must be an integer from 1"),
            std::string::npos)
      << outcome.log;
}

TEST(WorkerProtocolTest, AWorkerWaitsThroughAProxysBadGateway) {
  json reply = {{"id", "w-1"},
                {"secret", "the-secret-of-w-1"},
                {"heartbeat_interval_s", 5},
                {"lease_timeout_s", 30},
                {"protocol", kWorkerProtocolVersion}};
  reply["limits"] = protocol::to_json(ProtocolLimits{});
  OtherCoordinator coordinator(reply, 3);
  const fs::path log = fs::temp_directory_path() /
                       ("tessera-worker-protocol-" + std::to_string(::getpid()) + "-proxy.log");
  test::Process worker(TESSERA_WORKER_BIN,
                       {"--server", coordinator.url(), "--threads", "1", "--name", "proxied"}, log);
  // Registered once the proxy let it through, and went on to claim.
  EXPECT_TRUE(test::eventually([&] { return coordinator.claims() > 0; }, 20s))
      << "the worker gave up at a 502";
  EXPECT_EQ(coordinator.claim_secret(), "the-secret-of-w-1")
      << "the claim did not prove the worker";
  worker.signal(SIGTERM);
  EXPECT_TRUE(worker.wait_for(20s).has_value());
}

TEST(WorkerProtocolTest, AnyServerUrlIsOneLineAndAnExitCode) {
  // (https:// is a server URL like any other: farm_tls_test.cpp.) An unreadable CA file is
  // a usage error too.
  for (const auto& [url, code] :
       std::vector<std::pair<std::string, int>>{{"https://127.0.0.1:1 --ca-file /nonexistent", 2},
                                                {"ftp://127.0.0.1", 2},
                                                {"http://", 2},
                                                {"http://[::1", 2}}) {
    const fs::path log = fs::temp_directory_path() /
                         ("tessera-worker-protocol-" + std::to_string(::getpid()) + "-url.log");
    fs::remove(log);
    std::optional<int> status;
    {
      std::vector<std::string> args{"--server", url.substr(0, url.find(' '))};
      if (url.find(' ') != std::string::npos)
        args.insert(args.end(), {"--ca-file", url.substr(url.rfind(' ') + 1)});
      test::Process worker(TESSERA_WORKER_BIN, args, log);
      status = worker.wait_for(20s);
    }
    std::ifstream in(log);
    const std::string output{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    ASSERT_TRUE(status && WIFEXITED(*status)) << url << ": " << output;
    EXPECT_EQ(WEXITSTATUS(*status), code) << url << ": " << output;
    EXPECT_EQ(output.rfind("error: ", 0), 0u) << output;
    EXPECT_EQ(output.find('\n'), output.size() - 1) << output;
  }
}

TEST(ProtocolLimitsTest, TheirJsonRoundTripsAndEveryLimitIsRequired) {
  ProtocolLimits limits = coordinator_limits(4096);
  EXPECT_EQ(limits.max_result_bytes, std::size_t{4096} * 4096 * 12);
  EXPECT_EQ(coordinator_limits(64).max_result_bytes, std::size_t{64} << 20);
  const auto read = [](const json& body) {
    return protocol::read_limits(protocol::FieldReader(body));
  };
  EXPECT_EQ(read(protocol::to_json(limits)), limits);
  for (const char* key :
       {"max_result_tiles", "max_result_bytes", "max_batch_tiles", "max_lease_tiles"}) {
    json missing = protocol::to_json(limits);
    missing.erase(key);
    EXPECT_THROW(read(missing), protocol::ProtocolError) << key;
    json negative = protocol::to_json(limits);
    negative[key] = -1;
    EXPECT_THROW(read(negative), protocol::ProtocolError) << key;
  }
  json huge = protocol::to_json(limits);
  huge["max_result_tiles"] = std::uint64_t{1} << 40;  // past an int
  EXPECT_THROW(read(huge), protocol::ProtocolError);
  EXPECT_EQ(with_thousands(1365), "1,365");
  EXPECT_EQ(with_thousands(999), "999");
  EXPECT_EQ(with_thousands(68157440), "68,157,440");
  EXPECT_EQ(result_tiles_over_limit(limits, 1365),
            "a result carries at most 256 tiles; this one has 1,365");
}

}  // namespace
}  // namespace tessera
