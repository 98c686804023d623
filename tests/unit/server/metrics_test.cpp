// GET /metrics on its own: the exposition format of histograms and HTTP counts, labels that
// strangers cannot multiply, and who is answered.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <filesystem>

#include <gtest/gtest.h>
#include <boost/asio/io_context.hpp>

#include "server/api/access.hpp"
#include "server/api/api_routes.hpp"
#include "server/farm/sqlite_store.hpp"
#include "server/metrics/histogram.hpp"
#include "server/metrics/http_metrics.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;

TEST(MetricsTest, AHistogramCountsEachValueInItsBucketAndTheOnesAbove) {
  Histogram histogram({0.01, 0.1, 1});
  for (const double value : {0.005, 0.01, 0.05, 2.0}) histogram.observe(value);
  std::string out;
  histogram.write(out, "t_seconds", "route=\"/x\"");
  EXPECT_EQ(out,
            "t_seconds_bucket{route=\"/x\",le=\"0.01\"} 2\n"
            "t_seconds_bucket{route=\"/x\",le=\"0.10000000000000001\"} 3\n"
            "t_seconds_bucket{route=\"/x\",le=\"1\"} 3\n"
            "t_seconds_bucket{route=\"/x\",le=\"+Inf\"} 4\n"
            "t_seconds_sum{route=\"/x\"} 2.0649999999999999\n"
            "t_seconds_count{route=\"/x\"} 4\n");
}

TEST(MetricsTest, RequestsAreCountedByPatternMethodAndStatusNeverByTheirOwnPath) {
  HttpMetrics metrics;
  metrics.record("/v1/jobs/{id}", "GET", 200, 0.002);
  metrics.record("/v1/jobs/{id}", "GET", 200, 0.003);
  metrics.record("/v1/jobs/{id}", "GET", 404, 0.001);
  metrics.record("", "BREW", 405, 0);  // matched no route, with a method of its own
  metrics.record("", "GET\"}", 404, 0);
  std::string out;
  metrics.write(out);
  EXPECT_NE(out.find("tessera_http_requests_total{route=\"/v1/jobs/{id}\",method=\"GET\","
                     "status=\"200\"} 2\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("{route=\"unmatched\",method=\"other\",status=\"405\"} 1\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("{route=\"unmatched\",method=\"other\",status=\"404\"} 1\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("tessera_http_request_duration_seconds_count{route=\"/v1/jobs/{id}\"} 3\n"),
            std::string::npos)
      << out;
  EXPECT_EQ(label_value("a\"b\\c\nd"), "a\\\"b\\\\c\\nd");
}

TEST(MetricsTest, OnlyTheMetricsTokenOpensTheMetricsRole) {
  const AccessPolicy open(AccessTokens{"api", "worker", ""});
  EXPECT_FALSE(open.protects(role_metrics)) << "without a token, the route answers loopback only";
  const AccessPolicy policy(AccessTokens{"api", "worker", "scrape"});
  EXPECT_FALSE(policy.check(role_metrics, "Bearer scrape"));
  for (const char* other : {"", "Bearer api", "Bearer worker", "Bearer scrapes"}) {
    const auto refused = policy.check(role_metrics, other);
    ASSERT_TRUE(refused) << other;
    EXPECT_EQ(refused->status, 401) << other;
  }
  EXPECT_EQ(policy.check(role_client, "Bearer scrape")->status, 401)
      << "the metrics token opens nothing else";
}

class MetricsRouteTest : public ::testing::Test {
 protected:
  MetricsRouteTest()
      : dir_(fs::temp_directory_path() / ("tessera-metrics-" + std::to_string(::getpid()))),
        store_((fs::remove_all(dir_), dir_)),
        scheduler_(store_, clock_),
        claims_(io_),
        job_waits_(io_),
        context_{scheduler_, clock_, claims_, job_waits_, Limits{}, 1 << 20, dir_ / "tmp"} {
    context_.data_dir = dir_;
    add_api_routes(router_, context_);
  }
  ~MetricsRouteTest() override { fs::remove_all(dir_); }

  // The answer to GET /metrics from `peer`.
  HttpResponse scrape(const std::string& peer) {
    const RouteMatch match = router_.match("GET", "/metrics");
    EXPECT_TRUE(match.handler);
    EXPECT_EQ(match.role, role_metrics);
    HttpRequest request;
    request.remote_address = peer;
    HttpResponse answer;
    (*match.handler)(std::move(request),
                     [&](HttpResponse response) { answer = std::move(response); });
    return answer;
  }

  fs::path dir_;
  SqliteStore store_;
  ManualClock clock_;
  Scheduler scheduler_;
  boost::asio::io_context io_;
  LongPolls claims_;
  LongPolls job_waits_;
  ApiContext context_;
  Router router_;
};

TEST_F(MetricsRouteTest, WithoutATokenOnlyThisMachineIsAnswered) {
  for (const char* local : {"127.0.0.1:5000", "127.8.9.10:1", "[::1]:5000", "[::ffff:127.0.0.1]:7"})
    EXPECT_EQ(scrape(local).status, 200) << local;
  for (const char* remote :
       {"10.0.0.7:5000", "[2001:db8::1]:5000", "[::ffff:10.0.0.7]:7", "junk"}) {
    const HttpResponse answer = scrape(remote);
    EXPECT_EQ(answer.status, 403) << remote;
    EXPECT_NE(answer.body.find("metrics_refused"), std::string::npos) << answer.body;
  }
  // With a token, the access policy checks it before the route; any peer may then ask.
  context_.metrics_loopback_only = false;
  EXPECT_EQ(scrape("10.0.0.7:5000").status, 200);
}

TEST_F(MetricsRouteTest, EveryJobStateAndWorkerStateIsAlwaysASeries) {
  const HttpResponse answer = scrape("127.0.0.1:1");
  EXPECT_EQ(answer.content_type, "text/plain; version=0.0.4; charset=utf-8");
  for (const char* state : {"queued", "running", "paused", "completed", "failed", "canceled"})
    EXPECT_NE(answer.body.find(std::string("tessera_jobs{state=\"") + state + "\"} 0\n"),
              std::string::npos)
        << state;
  for (const char* state : {"idle", "rendering", "draining", "gone", "left"})
    EXPECT_NE(answer.body.find(std::string("tessera_workers{state=\"") + state + "\"} 0\n"),
              std::string::npos)
        << state;
  EXPECT_NE(answer.body.find("# TYPE tessera_tile_render_seconds histogram\n"), std::string::npos);
  EXPECT_NE(answer.body.find("tessera_tile_render_seconds_count 0\n"), std::string::npos);
}

}  // namespace
}  // namespace tessera
