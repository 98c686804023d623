// Every route of docs/openapi.yaml: the patterns the coordinator serves, and the targets
// (path and query) the clients send. An id is data, never part of the path's structure:
// it is percent-encoded into its segment.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "common/image_format.hpp"
#include "common/protocol/job_state.hpp"

namespace tessera::protocol {

namespace route {
inline constexpr std::string_view healthz = "/healthz";
inline constexpr std::string_view readyz = "/readyz";
inline constexpr std::string_view jobs = "/v1/jobs";
inline constexpr std::string_view job = "/v1/jobs/{id}";
inline constexpr std::string_view job_image = "/v1/jobs/{id}/image";
inline constexpr std::string_view job_cancel = "/v1/jobs/{id}/cancel";
inline constexpr std::string_view workers = "/v1/workers";
inline constexpr std::string_view worker = "/v1/workers/{id}";
inline constexpr std::string_view worker_claim = "/v1/workers/{id}/claim";
inline constexpr std::string_view scene = "/v1/scenes/{digest}";
inline constexpr std::string_view lease_heartbeat = "/v1/leases/{id}/heartbeat";
inline constexpr std::string_view lease_extend = "/v1/leases/{id}/extend";
inline constexpr std::string_view lease_result = "/v1/leases/{id}/result";
inline constexpr std::string_view lease_fail = "/v1/leases/{id}/fail";
inline constexpr std::string_view lease_release = "/v1/leases/{id}/release";
// Assets (mesh files, their MTL and .bin) by digest, "sha256:<64 hex digits>": uploaded and
// looked up by clients, fetched by workers from the second.
inline constexpr std::string_view asset = "/v1/assets/{digest}";
inline constexpr std::string_view scene_asset = "/v1/scene-assets/{digest}";
// Every one of them, for the contract test.
inline constexpr std::string_view all[] = {
    healthz,      readyz,     jobs,          job,   job_image,       job_cancel,
    workers,      worker,     worker_claim,  scene, lease_heartbeat, lease_extend,
    lease_result, lease_fail, lease_release, asset, scene_asset};
}  // namespace route

// The names of the routes' query parameters.
namespace query {
inline constexpr std::string_view wait_s = "wait_s";
inline constexpr std::string_view max_tiles = "max_tiles";
inline constexpr std::string_view state = "state";
inline constexpr std::string_view limit = "limit";
inline constexpr std::string_view format = "format";
inline constexpr std::string_view partial = "partial";
}  // namespace query

// The name of a route's one parameter: "id" or "digest".
std::string_view parameter_of(std::string_view pattern);
// The pattern with its parameter replaced by `value`, percent-encoded.
std::string fill(std::string_view pattern, std::string_view value);

// Targets with their queries.
std::string job_target(std::string_view id, double wait_s = 0);
std::string jobs_target(std::optional<JobState> state, int limit);
std::string image_target(std::string_view id, const ImageFormat& format, bool partial);
std::string claim_target(std::string_view worker, double wait_s, int max_tiles);
std::string extend_target(std::string_view lease, int max_tiles);

}  // namespace tessera::protocol
