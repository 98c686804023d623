#include "server/metrics/http_metrics.hpp"

#include <array>

namespace tessera {
namespace {

constexpr std::array<std::string_view, 7> kMethods = {"GET",   "HEAD",   "POST",   "PUT",
                                                      "PATCH", "DELETE", "OPTIONS"};

std::string_view method_label(std::string_view method) {
  for (const std::string_view known : kMethods)
    if (known == method) return known;
  return "other";
}

}  // namespace

std::string label_value(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (c == '\\')
      out += "\\\\";
    else if (c == '"')
      out += "\\\"";
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
  return out;
}

void HttpMetrics::record(std::string_view route, std::string_view method, int status,
                         double seconds) {
  const std::string route_label = route.empty() ? "unmatched" : std::string(route);
  std::lock_guard lock(mutex_);
  requests_[{route_label, std::string(method_label(method)), status}] += 1;
  auto& histogram = latency_[route_label];
  // From a millisecond to a minute: long polls (claims, ?wait_s=) wait up to one.
  if (!histogram)
    histogram = std::make_unique<Histogram>(std::vector<double>{
        0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60});
  histogram->observe(seconds);
}

void HttpMetrics::write(std::string& out) const {
  std::lock_guard lock(mutex_);
  out +=
      "# HELP tessera_http_requests_total HTTP requests answered, by route pattern, method "
      "and status.\n# TYPE tessera_http_requests_total counter\n";
  for (const auto& [key, count] : requests_) {
    const auto& [route, method, status] = key;
    out += "tessera_http_requests_total{route=\"" + label_value(route) + "\",method=\"" + method +
           "\",status=\"" + std::to_string(status) + "\"} " + std::to_string(count) + "\n";
  }
  out +=
      "# HELP tessera_http_request_duration_seconds From a request's header to its answer, "
      "by route pattern (long polls included).\n"
      "# TYPE tessera_http_request_duration_seconds histogram\n";
  for (const auto& [route, histogram] : latency_)
    histogram->write(out, "tessera_http_request_duration_seconds",
                     "route=\"" + label_value(route) + "\"");
}

}  // namespace tessera
