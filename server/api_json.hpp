// The JSON shapes of docs/openapi.yaml, built from the scheduler's records.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "server/scheduler.hpp"

namespace tessera {

// RFC 3339 UTC with milliseconds, e.g. 2026-11-22T01:02:03.456Z.
std::string format_timestamp(std::int64_t ms_since_epoch);

// Names (of jobs, workers, hosts) are for people and appear in every listing: a name of
// megabytes would make each list that large.
inline constexpr std::size_t max_name_bytes = 256;

nlohmann::json to_json(const JobStatus& job, std::int64_t now_ms);
nlohmann::json to_json(const WorkerInfo& worker);
nlohmann::json to_json(const Lease& lease, std::int64_t now_ms);

}  // namespace tessera
