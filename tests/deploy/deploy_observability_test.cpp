// deploy/grafana and deploy/prometheus: the Grafana dashboard is a dashboard Grafana can
// import (valid JSON, one id per panel, each panel placed on the grid, one Prometheus data
// source chosen on import) that asks only for metrics the coordinator's GET /metrics
// serves, the queue depth first; and the example Prometheus configuration scrapes
// /metrics on the coordinator's Service port, with the metrics token.
#include <map>
#include <regex>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/deploy/deploy_yaml.hpp"

namespace tessera {
namespace {

using test::text_of;
using test::texts_of;

enum class MetricType { gauge, counter, histogram };

// The metrics of the coordinator's GET /metrics (docs/api.md, "Metrics"), by name.
const std::map<std::string, MetricType>& coordinator_metrics() {
  static const std::map<std::string, MetricType> metrics = {
      {"tessera_jobs", MetricType::gauge},
      {"tessera_pending_tiles", MetricType::gauge},
      {"tessera_tiles_rendered_total", MetricType::counter},
      {"tessera_tile_render_seconds", MetricType::histogram},
      {"tessera_lease_expiries_total", MetricType::counter},
      {"tessera_tile_retries_total", MetricType::counter},
      {"tessera_workers", MetricType::gauge},
      {"tessera_rays_total", MetricType::counter},
      {"tessera_http_requests_total", MetricType::counter},
      {"tessera_http_request_duration_seconds", MetricType::histogram},
      {"tessera_sqlite_bytes", MetricType::gauge},
      {"tessera_asset_store_bytes", MetricType::gauge},
  };
  return metrics;
}

// The metric a series name in a query belongs to: itself, or for a histogram's series
// (NAME_bucket, NAME_sum, NAME_count) the histogram's name. Empty for an unknown name, and
// for a histogram named bare, which is no series at all.
std::string metric_of_series(const std::string& series) {
  const auto& metrics = coordinator_metrics();
  if (const auto found = metrics.find(series); found != metrics.end())
    return found->second == MetricType::histogram ? "" : series;
  for (const std::string suffix : {"_bucket", "_sum", "_count"}) {
    if (!series.ends_with(suffix)) continue;
    const std::string base = series.substr(0, series.size() - suffix.size());
    if (const auto found = metrics.find(base);
        found != metrics.end() && found->second == MetricType::histogram)
      return base;
  }
  return "";
}

const std::string dashboard_file = "deploy/grafana/tessera-dashboard.json";
const std::string prometheus_file = "deploy/prometheus/prometheus.yml";

nlohmann::json dashboard() { return nlohmann::json::parse(test::read_source(dashboard_file)); }

// Every panel, those inside collapsed rows too.
std::vector<nlohmann::json> panels_of(const nlohmann::json& holder) {
  std::vector<nlohmann::json> all;
  if (!holder.contains("panels") || !holder["panels"].is_array()) return all;
  for (const nlohmann::json& panel : holder["panels"]) {
    all.push_back(panel);
    for (const nlohmann::json& inner : panels_of(panel)) all.push_back(inner);
  }
  return all;
}

// Every query of every panel, with its panel's title.
std::vector<std::pair<std::string, std::string>> queries_of(const nlohmann::json& board) {
  std::vector<std::pair<std::string, std::string>> queries;
  for (const nlohmann::json& panel : panels_of(board))
    for (const nlohmann::json& target : panel.value("targets", nlohmann::json::array()))
      queries.emplace_back(panel.value("title", ""), target.value("expr", ""));
  return queries;
}

std::vector<std::string> series_in(const std::string& expr) {
  static const std::regex name(R"(tessera_[a-z_]+)");
  std::vector<std::string> names;
  for (auto it = std::sregex_iterator(expr.begin(), expr.end(), name); it != std::sregex_iterator();
       ++it)
    names.push_back(it->str());
  return names;
}

TEST(DeployObservabilityTest, TheDashboardIsOneGrafanaCanImport) {
  nlohmann::json board;
  ASSERT_NO_THROW(board = dashboard()) << dashboard_file << " is not valid JSON";
  EXPECT_EQ(board.value("schemaVersion", 0), 39);
  EXPECT_FALSE(board.value("title", "").empty());
  const auto panels = panels_of(board);
  ASSERT_FALSE(panels.empty());

  std::set<int> ids;
  for (const nlohmann::json& panel : panels) {
    const std::string title = panel.value("title", "");
    ASSERT_TRUE(panel.contains("id") && panel["id"].is_number_integer()) << title << ": no id";
    EXPECT_TRUE(ids.insert(panel["id"].get<int>()).second)
        << title << ": panel id " << panel["id"] << " is used twice";
    const nlohmann::json grid = panel.value("gridPos", nlohmann::json::object());
    for (const char* key : {"h", "w", "x", "y"})
      EXPECT_TRUE(grid.contains(key) && grid[key].is_number_integer())
          << title << ": gridPos." << key;
    EXPECT_GT(grid.value("w", 0), 0) << title;
    EXPECT_GT(grid.value("h", 0), 0) << title;
    EXPECT_LE(grid.value("x", 0) + grid.value("w", 0), 24) << title << " is wider than the grid";
  }
  // No two panels on the same cells (rows excepted: Grafana stacks them).
  for (std::size_t i = 0; i < panels.size(); ++i)
    for (std::size_t j = i + 1; j < panels.size(); ++j) {
      const nlohmann::json a = panels[i].value("gridPos", nlohmann::json::object());
      const nlohmann::json b = panels[j].value("gridPos", nlohmann::json::object());
      if (panels[i].value("type", "") == "row" || panels[j].value("type", "") == "row") continue;
      const bool apart = a.value("x", 0) + a.value("w", 0) <= b.value("x", 0) ||
                         b.value("x", 0) + b.value("w", 0) <= a.value("x", 0) ||
                         a.value("y", 0) + a.value("h", 0) <= b.value("y", 0) ||
                         b.value("y", 0) + b.value("h", 0) <= a.value("y", 0);
      EXPECT_TRUE(apart) << panels[i].value("title", "") << " and " << panels[j].value("title", "")
                         << " overlap";
    }
}

TEST(DeployObservabilityTest, TheDashboardAsksForItsPrometheusOnImport) {
  const nlohmann::json board = dashboard();
  bool variable = false;
  const nlohmann::json templating = board.value("templating", nlohmann::json::object());
  for (const nlohmann::json& entry : templating.value("list", nlohmann::json::array()))
    variable = variable || (entry.value("name", "") == "DS_PROMETHEUS" &&
                            entry.value("type", "") == "datasource" &&
                            entry.value("query", "") == "prometheus");
  EXPECT_TRUE(variable) << "no templating variable DS_PROMETHEUS of type datasource";
  // Every query goes to that data source, none to one of the machine it was made on.
  for (const nlohmann::json& panel : panels_of(board)) {
    const std::string title = panel.value("title", "");
    if (panel.value("type", "") == "row") continue;
    const auto uid = [](const nlohmann::json& holder) {
      const nlohmann::json source = holder.value("datasource", nlohmann::json::object());
      return source.is_object() ? source.value("uid", "") : std::string();
    };
    EXPECT_EQ(uid(panel), "${DS_PROMETHEUS}") << title;
    for (const nlohmann::json& target : panel.value("targets", nlohmann::json::array()))
      if (target.contains("datasource")) {
        EXPECT_EQ(uid(target), "${DS_PROMETHEUS}") << title;
      }
  }
}

TEST(DeployObservabilityTest, TheDashboardQueriesOnlyTheCoordinatorsMetrics) {
  const auto queries = queries_of(dashboard());
  ASSERT_FALSE(queries.empty());
  std::set<std::string> shown;
  for (const auto& [title, expr] : queries) {
    const auto names = series_in(expr);
    EXPECT_FALSE(names.empty()) << title << ": " << expr << " reads no tessera_ metric";
    for (const std::string& series : names) {
      const std::string metric = metric_of_series(series);
      EXPECT_FALSE(metric.empty())
          << title << ": " << series << " is not a series of the coordinator's GET /metrics";
      shown.insert(metric);
    }
  }
  // The queue depth, the workers' autoscaling signal, above all.
  EXPECT_TRUE(shown.contains("tessera_pending_tiles")) << "the dashboard shows no queue depth";
  for (const auto& [metric, type] : coordinator_metrics())
    EXPECT_TRUE(shown.contains(metric)) << "no panel shows " << metric;
}

TEST(DeployObservabilityTest, PrometheusScrapesTheCoordinatorsMetricsWithTheToken) {
  std::vector<YAML::Node> documents;
  ASSERT_NO_THROW(documents = test::load_yaml(prometheus_file));
  ASSERT_EQ(documents.size(), 1u);
  YAML::Node job;
  for (const YAML::Node& scrape : documents[0]["scrape_configs"])
    if (text_of(scrape["job_name"]) == "tessera") job = scrape;
  ASSERT_TRUE(test::is_map(job)) << prometheus_file << " has no scrape job `tessera`";
  EXPECT_EQ(text_of(job["metrics_path"]), "/metrics");
  // Off loopback, the coordinator answers /metrics only with the metrics token, read from
  // a file rather than written into the configuration.
  EXPECT_EQ(text_of(job["authorization"]["type"]), "Bearer");
  EXPECT_FALSE(text_of(job["authorization"]["credentials_file"]).empty());
  EXPECT_FALSE(job["authorization"]["credentials"].IsDefined()) << "a token in the file";

  // The target is the coordinator's Service in deploy/k8s, on its port.
  const auto services = test::of_kind(test::load_yaml("deploy/k8s/coordinator.yaml"), "Service");
  ASSERT_EQ(services.size(), 1u);
  const std::string service = text_of(services[0]["metadata"]["name"]);
  const std::string port = text_of(services[0]["spec"]["ports"][0]["port"]);
  ASSERT_EQ(test::size_of(job["static_configs"]), 1u);
  const auto targets = texts_of(job["static_configs"][0]["targets"]);
  ASSERT_EQ(targets.size(), 1u);
  EXPECT_EQ(targets[0].substr(0, targets[0].find_first_of(".:")), service) << targets[0];
  EXPECT_EQ(targets[0].substr(targets[0].rfind(':') + 1), port) << targets[0];
}

}  // namespace
}  // namespace tessera
