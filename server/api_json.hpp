// The JSON shapes of docs/openapi.yaml, built from the scheduler's records.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>

#include <nlohmann/json.hpp>

#include "server/http_types.hpp"
#include "server/scheduler.hpp"

namespace tessera {

// RFC 3339 UTC with milliseconds, e.g. 2026-11-22T01:02:03.456Z.
std::string format_timestamp(std::int64_t ms_since_epoch);

// Names (of jobs, workers, hosts) are for people and appear in every listing: a name of
// megabytes would make each list that large.
inline constexpr std::size_t max_name_bytes = 256;

// The request's JSON body, or the 400 malformed_json answer naming line and column.
std::variant<nlohmann::json, HttpResponse> json_body(const HttpRequest& request);

// A long poll's ?wait_s= (0 to 60 seconds; `fallback` when absent), or nothing when it is
// not such a number.
std::optional<std::chrono::milliseconds> wait_of(const HttpRequest& request, double fallback_s);
inline HttpResponse bad_wait() {
  return error_response(400, "invalid_request", "wait_s must be a number from 0 to 60");
}

nlohmann::json to_json(const JobStatus& job, std::int64_t now_ms);
nlohmann::json to_json(const WorkerInfo& worker);
nlohmann::json to_json(const Lease& lease, std::int64_t now_ms);

}  // namespace tessera
