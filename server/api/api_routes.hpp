// The public API of docs/openapi.yaml, as route handlers over the Scheduler.
#pragma once

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>

#include "common/scene/scene.hpp"
#include "server/api/long_polls.hpp"
#include "server/api/readiness.hpp"
#include "server/api/submit_budget.hpp"
#include "server/farm/clock.hpp"
#include "server/farm/scheduler.hpp"
#include "server/http/router.hpp"

namespace tessera {

class AssetStore;
class EventHub;
class HttpMetrics;

struct ApiContext {
  Scheduler& scheduler;
  const Clock& clock;
  LongPolls& claims;     // parked claims, woken when tiles may be available
  LongPolls& job_waits;  // parked GET /v1/jobs/{id}?wait_s=, woken when a job finishes
  Limits limits;
  std::size_t max_job_body_bytes = 64 << 20;
  std::filesystem::path temp_dir;         // where images are encoded before they are sent
  std::atomic<unsigned> temp_counter{0};  // unique temporary names under temp_dir
  // Runs work that waits on the disk (encoding an image) off the network's threads and the
  // store thread; at once, on the calling thread, where nothing else is given.
  std::function<void(std::function<void()>)> run_blocking = [](const std::function<void()>& work) {
    work();
  };
  // Runs work that reads or writes assets (an upload's pieces, a submission's mesh files)
  // off the network's threads, apart from image encoding; at once where nothing is given.
  std::function<void(std::function<void()>)> run_disk = [](const std::function<void()>& work) {
    work();
  };
  // The memory job submissions being read may take together; none: no cap.
  SubmitBudget* submit_budget = nullptr;
  // Mesh files and the files they name, by digest; none: no asset routes, and a scene
  // that names an asset is refused.
  AssetStore* assets = nullptr;
  // GET /metrics: the HTTP layer's counts (none: not served), and whether the route is
  // open to loopback peers only (no --metrics-token).
  const HttpMetrics* http_metrics = nullptr;
  bool metrics_loopback_only = true;
  std::filesystem::path data_dir = {};  // whose files /metrics sizes
  EventHub* events = nullptr;           // server-sent events; none: not served
  bool api_token_required = false;      // the client routes want the API token (/healthz)
};

// One file per resource, each named for it: job_routes.cpp and so on.
void add_job_routes(Router& router, ApiContext& context);     // /v1/jobs...
void add_worker_routes(Router& router, ApiContext& context);  // /v1/workers...
void add_scene_routes(Router& router, ApiContext& context);   // /v1/scenes/{digest}
void add_lease_routes(Router& router, ApiContext& context);   // /v1/leases/{id}/...
void add_asset_routes(Router& router, ApiContext& context);   // /v1/assets, /v1/scene-assets
// Priority, pause, resume, retry; drain and remove workers (control_routes.cpp).
void add_control_routes(Router& router, ApiContext& context);
// GET /metrics, in Prometheus's text format (metrics_route.cpp).
void add_metrics_route(Router& router, ApiContext& context);
// Server-sent events and a job's tiles (event_routes.cpp).
void add_event_routes(Router& router, ApiContext& context);
// The web dashboard: its page at /, /jobs/{id} and /workers, and /ui/... (web_routes.cpp).
void add_web_routes(Router& router, ApiContext& context);
// /healthz and /readyz. Without a Readiness, /readyz never reports ready: only a caller
// that knows start-up is over (server_main) can say so.
void add_health_routes(Router& router, const Readiness* readiness = nullptr,
                       bool api_token_required = false);
// Every route of docs/openapi.yaml, as the coordinator serves them (the asset routes only
// with an AssetStore in `context`).
void add_api_routes(Router& router, ApiContext& context, const Readiness* readiness = nullptr);

}  // namespace tessera
