// The coordinator's HTTP requests for GET /metrics: counted by route, method and status,
// with each route's latency. Labels come from the router's patterns and a fixed set of
// methods, never from a request's own path: a stranger's requests cannot make series.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <tuple>

#include "server/metrics/histogram.hpp"

namespace tessera {

class HttpMetrics {
 public:
  // `route`: the matched route's pattern, or "" for a request that matched none.
  void record(std::string_view route, std::string_view method, int status, double seconds);
  // tessera_http_requests_total and tessera_http_request_duration_seconds, in the text
  // exposition format.
  void write(std::string& out) const;

 private:
  mutable std::mutex mutex_;
  std::map<std::tuple<std::string, std::string, int>, std::uint64_t> requests_;
  std::map<std::string, std::unique_ptr<Histogram>> latency_;
};

// A label value as the exposition format quotes it: backslash, double quote and newline
// escaped.
std::string label_value(std::string_view text);

}  // namespace tessera
