// Every route of docs/openapi.yaml: the patterns the coordinator serves, and the targets
// (path and query) the clients send. An id is data, never part of the path's structure:
// it is percent-encoded into its segment.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "common/protocol/image_format.hpp"
#include "common/protocol/job_state.hpp"

namespace tessera::protocol {

namespace route {
inline constexpr std::string_view healthz = "/healthz";
inline constexpr std::string_view readyz = "/readyz";
inline constexpr std::string_view metrics = "/metrics";  // Prometheus's text format
inline constexpr std::string_view jobs = "/v1/jobs";
inline constexpr std::string_view job = "/v1/jobs/{id}";
inline constexpr std::string_view job_image = "/v1/jobs/{id}/image";
inline constexpr std::string_view job_cancel = "/v1/jobs/{id}/cancel";
inline constexpr std::string_view job_pause = "/v1/jobs/{id}/pause";
inline constexpr std::string_view job_resume = "/v1/jobs/{id}/resume";
inline constexpr std::string_view job_retry = "/v1/jobs/{id}/retry";
inline constexpr std::string_view job_tiles = "/v1/jobs/{id}/tiles";
// An animation's frames, and each frame's image (a still's one frame is frame 0).
inline constexpr std::string_view job_frames = "/v1/jobs/{id}/frames";
inline constexpr std::string_view job_frame_image = "/v1/jobs/{id}/frames/{frame}/image";
// Server-sent events: the farm's, and one job's.
inline constexpr std::string_view events = "/v1/events";
inline constexpr std::string_view job_events = "/v1/jobs/{id}/events";
inline constexpr std::string_view workers = "/v1/workers";
inline constexpr std::string_view worker = "/v1/workers/{id}";
inline constexpr std::string_view worker_claim = "/v1/workers/{id}/claim";
// The farm's controls of a worker (the client's, not the worker's own).
inline constexpr std::string_view worker_drain = "/v1/workers/{id}/drain";
inline constexpr std::string_view worker_undrain = "/v1/workers/{id}/undrain";
inline constexpr std::string_view worker_remove = "/v1/workers/{id}/remove";
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
// The web dashboard (server/api/web_routes.cpp): its page, at the paths of its views, and the
// files the page loads (its script's modules, its style), each by its name in server/web/.
inline constexpr std::string_view ui_page = "/";
inline constexpr std::string_view ui_job = "/jobs/{id}";
inline constexpr std::string_view ui_workers = "/workers";
inline constexpr std::string_view ui_file = "/ui/{name}";
// Every one of them, for the contract test.
inline constexpr std::string_view all[] = {
    healthz,      readyz,          metrics,       events,  job_events,      job_tiles,
    job_frames,   job_frame_image, jobs,          job,     job_image,       job_cancel,
    job_pause,    job_resume,      job_retry,     workers, worker,          worker_claim,
    worker_drain, worker_undrain,  worker_remove, scene,   lease_heartbeat, lease_extend,
    lease_result, lease_fail,      lease_release, asset,   scene_asset,     ui_page,
    ui_job,       ui_workers,      ui_file};
}  // namespace route

// The names of the routes' query parameters.
namespace query {
inline constexpr std::string_view wait_s = "wait_s";
inline constexpr std::string_view max_tiles = "max_tiles";
inline constexpr std::string_view state = "state";
inline constexpr std::string_view limit = "limit";
inline constexpr std::string_view format = "format";
inline constexpr std::string_view partial = "partial";
inline constexpr std::string_view id_prefix = "id_prefix";
inline constexpr std::string_view name = "name";
inline constexpr std::string_view offset = "offset";
}  // namespace query

// The name of a route's one parameter: "id" or "digest".
std::string_view parameter_of(std::string_view pattern);
// The pattern with its parameter replaced by `value`, percent-encoded.
std::string fill(std::string_view pattern, std::string_view value);

// Targets with their queries.
std::string job_target(std::string_view id, double wait_s = 0);
std::string jobs_target(std::optional<JobState> state, int limit);
// The jobs whose id begins with `prefix` (at most `limit`).
std::string jobs_with_prefix_target(std::string_view prefix, int limit);
// GET /v1/jobs of the jobs named exactly `name`, newest first, at most `limit`.
std::string jobs_named_target(std::string_view name, int limit);
std::string image_target(std::string_view id, const ImageFormat& format, bool partial);
// The image of one frame of the job.
std::string frame_image_target(std::string_view id, int frame, const ImageFormat& format,
                               bool partial);
std::string claim_target(std::string_view worker, double wait_s, int max_tiles);
std::string extend_target(std::string_view lease, int max_tiles);

}  // namespace tessera::protocol
