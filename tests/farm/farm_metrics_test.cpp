// GET /metrics on a real coordinator: what it says after a job, whom it answers, and a real
// Prometheus (Debian's) scraping it and answering queries about the farm.
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"
#include "tests/unused_port.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

// "name{labels} value" lines by their series (name and labels as written).
std::map<std::string, double> samples_of(const std::string& text) {
  std::map<std::string, double> samples;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto space = line.rfind(' ');
    samples[line.substr(0, space)] = std::stod(line.substr(space + 1));
  }
  return samples;
}

std::map<std::string, double> scrape(Farm& farm, const HttpClient::Headers& headers = {}) {
  const HttpResult answer = farm.http(10s).request("GET", "/metrics", "", "", headers);
  EXPECT_EQ(answer.status, 200) << answer.body;
  EXPECT_EQ(answer.headers.at("content-type"), "text/plain; version=0.0.4; charset=utf-8");
  return samples_of(answer.body);
}

TEST(FarmMetricsTest, AfterAJobTheMetricsSayWhatTheFarmDid) {
  Farm farm("metrics-job", 1);
  const json job = farm.api().submit("counted", 70, test::showcase(64, 32, 1, 16));  // 8 tiles
  const json done = farm.wait_finished(job["id"]);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  // The worker's last upload is accepted before the job's status says completed.
  const auto m = scrape(farm);
  EXPECT_EQ(m.at("tessera_jobs{state=\"completed\"}"), 1);
  EXPECT_EQ(m.at("tessera_jobs{state=\"running\"}"), 0);
  EXPECT_EQ(m.at("tessera_jobs{state=\"paused\"}"), 0);
  EXPECT_EQ(m.at("tessera_tiles_rendered_total"), 8);
  EXPECT_EQ(m.at("tessera_rays_total"), done["stats"]["rays"].get<double>());
  // Every tile's time came with it, and none took as long as the whole job.
  EXPECT_EQ(m.at("tessera_tile_render_seconds_count"), 8);
  EXPECT_EQ(m.at("tessera_tile_render_seconds_bucket{le=\"+Inf\"}"), 8);
  EXPECT_GT(m.at("tessera_tile_render_seconds_sum"), 0);
  EXPECT_LT(m.at("tessera_tile_render_seconds_sum"), 8 * done["elapsed_s"].get<double>());
  EXPECT_EQ(m.count("tessera_pending_tiles{priority=\"70\"}"), 0u) << "no tile waits";
  EXPECT_EQ(m.at("tessera_lease_expiries_total"), 0);
  EXPECT_EQ(m.at("tessera_workers{state=\"draining\"}"), 0);
  EXPECT_EQ(m.at("tessera_workers{state=\"idle\"}") + m.at("tessera_workers{state=\"rendering\"}"),
            1);
  EXPECT_EQ(m.at("tessera_http_requests_total{route=\"/v1/jobs\",method=\"POST\",status=\"201\"}"),
            1);
  EXPECT_GE(m.at("tessera_http_request_duration_seconds_count{route=\"/v1/leases/{id}/result\"}"),
            1);
  EXPECT_GT(m.at("tessera_sqlite_bytes{file=\"database\"}"), 0);
  EXPECT_GT(m.at("tessera_sqlite_bytes{file=\"pixels\"}"), 64 * 32 * 12 - 1);
  EXPECT_EQ(m.at("tessera_asset_store_bytes"), 0);
  // A request's own path never becomes a label: unknown paths share one series.
  farm.http(10s).request("GET", "/no/such/path\"}", "", "");
  farm.http(10s).request("GET", "/another/one", "", "");
  const auto after = scrape(farm);
  EXPECT_EQ(
      after.at("tessera_http_requests_total{route=\"unmatched\",method=\"GET\",status=\"404\"}"),
      2);
}

TEST(FarmMetricsTest, PendingTilesAreTheQueueByPriorityWithoutPausedJobs) {
  Farm farm("metrics-queue", 0);  // no workers: every tile waits
  const std::string low = farm.api().submit("low", 20, test::showcase(32, 32, 1, 16))["id"];
  farm.api().submit("high", 90, test::showcase(64, 32, 1, 16));
  farm.api().submit("high too", 90, test::showcase(16, 16, 1, 16));
  auto m = scrape(farm);
  EXPECT_EQ(m.at("tessera_pending_tiles{priority=\"20\"}"), 4);
  EXPECT_EQ(m.at("tessera_pending_tiles{priority=\"90\"}"), 9);
  EXPECT_EQ(m.at("tessera_jobs{state=\"queued\"}"), 3);
  farm.api().pause(low);
  m = scrape(farm);
  EXPECT_EQ(m.count("tessera_pending_tiles{priority=\"20\"}"), 0u) << "paused: no worker is wanted";
  EXPECT_EQ(m.at("tessera_jobs{state=\"paused\"}"), 1);
  farm.api().set_priority(low, 90);
  farm.api().resume(low);
  EXPECT_EQ(scrape(farm).at("tessera_pending_tiles{priority=\"90\"}"), 13);
}

TEST(FarmMetricsTest, WithAMetricsTokenOnlyThatTokenReadsThem) {
  Farm farm("metrics-token", 0,
            {"--api-token", "api-secret", "--worker-token", "worker-secret", "--metrics-token",
             "scrape-secret"});
  HttpClient http = farm.http(10s);
  EXPECT_EQ(http.request("GET", "/metrics", "", "").status, 401);
  EXPECT_EQ(
      http.request("GET", "/metrics", "", "", {{"Authorization", "Bearer api-secret"}}).status, 401)
      << "the API token holds power over jobs; a scraper needs none";
  EXPECT_EQ(
      http.request("GET", "/metrics", "", "", {{"Authorization", "Bearer worker-secret"}}).status,
      401);
  scrape(farm, {{"Authorization", "Bearer scrape-secret"}});
  // And the metrics token opens nothing else.
  EXPECT_EQ(
      http.request("GET", "/v1/jobs", "", "", {{"Authorization", "Bearer scrape-secret"}}).status,
      401);
}

// One instant query of Prometheus's HTTP API: each series' value by its labels.
std::map<std::string, std::string> query(HttpClient& prometheus, const std::string& promql) {
  std::string encoded;
  for (const unsigned char c : promql) {
    if (std::isalnum(c) || c == '_') {
      encoded += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      encoded += hex;
    }
  }
  std::map<std::string, std::string> values;
  try {
    const HttpResult answer = prometheus.request("GET", "/api/v1/query?query=" + encoded, "", "");
    if (answer.status != 200) return values;
    const json body = json::parse(answer.body);
    for (const json& series : body["data"]["result"])
      values[series["metric"].dump()] = series["value"][1].get<std::string>();
  } catch (const std::exception&) {
    // Not up yet.
  }
  return values;
}

TEST(FarmMetricsTest, ARealPrometheusScrapesTheCoordinator) {
  const char* binary = "/usr/bin/prometheus";
  if (!std::filesystem::exists(binary))
    GTEST_SKIP() << "skipped: Debian's prometheus is not installed (deploy/install-deps.sh "
                    "installs it)";
  Farm farm("metrics-prometheus", 1, {"--metrics-token", "scrape-secret"});
  const json job = farm.api().submit("scraped", 60, test::showcase(64, 32, 1, 16));
  ASSERT_EQ(farm.wait_finished(job["id"])["state"], "completed");

  // Prometheus as people run it: a config file naming the target and the token's file.
  test::write_text(farm.dir() / "metrics.token", "scrape-secret\n");
  test::write_text(farm.dir() / "prometheus.yml",
                   "global:\n  scrape_interval: 1s\n"
                   "scrape_configs:\n"
                   "  - job_name: tessera\n"
                   "    metrics_path: /metrics\n"
                   "    authorization:\n"
                   "      type: Bearer\n"
                   "      credentials_file: " +
                       (farm.dir() / "metrics.token").string() +
                       "\n"
                       "    static_configs:\n"
                       "      - targets: ['127.0.0.1:" +
                       std::to_string(farm.port()) + "']\n");
  const int port = test::unused_port();
  test::Process prometheus(binary,
                           {"--config.file=" + (farm.dir() / "prometheus.yml").string(),
                            "--storage.tsdb.path=" + (farm.dir() / "tsdb").string(),
                            "--web.listen-address=127.0.0.1:" + std::to_string(port)},
                           farm.dir() / "prometheus.log");
  HttpClient api("http://127.0.0.1:" + std::to_string(port), 5s);
  // Once scraped, its own query API answers with the farm's series and their values.
  std::map<std::string, std::string> rendered;
  const bool scraped = test::eventually(
      [&] {
        rendered = query(api, "tessera_tiles_rendered_total");
        return !rendered.empty();
      },
      60s);
  ASSERT_TRUE(scraped) << test::read_text(farm.dir() / "prometheus.log");
  ASSERT_EQ(rendered.size(), 1u);
  EXPECT_EQ(rendered.begin()->second, "8");
  EXPECT_NE(rendered.begin()->first.find("\"job\":\"tessera\""), std::string::npos)
      << rendered.begin()->first;
  const auto completed = query(api, "tessera_jobs{state=\"completed\"}");
  ASSERT_EQ(completed.size(), 1u);
  EXPECT_EQ(completed.begin()->second, "1");
  const auto up = query(api, "up{job=\"tessera\"}");
  ASSERT_EQ(up.size(), 1u);
  EXPECT_EQ(up.begin()->second, "1");
  // The histogram is one Prometheus understands: a quantile of it is a number of seconds.
  const auto p50 = query(api, "histogram_quantile(0.5, tessera_tile_render_seconds_bucket)");
  ASSERT_EQ(p50.size(), 1u);
  EXPECT_GT(std::stod(p50.begin()->second), 0);
  const auto submits =
      query(api, "tessera_http_requests_total{route=\"/v1/jobs\",method=\"POST\",status=\"201\"}");
  ASSERT_EQ(submits.size(), 1u);
  EXPECT_EQ(submits.begin()->second, "1");
  prometheus.signal(SIGTERM);
  prometheus.wait_for(20s);
}

TEST(FarmMetricsTest, JsonLogsNameTheJobWorkerAndLeaseOfEachLine) {
  Farm farm("logs-json", 1, {"--log-format", "json", "--log-level", "info"});
  const std::string id = farm.api().submit("logged", 50, test::showcase(16, 16, 1, 16))["id"];
  ASSERT_EQ(farm.wait_finished(id)["state"], "completed");
  std::istringstream lines(test::read_text(farm.dir() / "server.log"));
  int lines_seen = 0, of_job = 0, of_worker = 0;
  for (std::string line; std::getline(lines, line);) {
    const json entry = json::parse(line, nullptr, false);
    ASSERT_TRUE(entry.is_object()) << "not one JSON object: " << line;
    ++lines_seen;
    EXPECT_TRUE(entry.contains("time") && entry.contains("level") && entry.contains("message"));
    of_job += entry.value("job", "") == id;
    of_worker += entry.contains("worker");
  }
  EXPECT_GT(lines_seen, 2);
  EXPECT_GE(of_job, 2) << "submitted, and completed";
  EXPECT_GE(of_worker, 1) << "a worker joined";
}

}  // namespace
}  // namespace tessera
