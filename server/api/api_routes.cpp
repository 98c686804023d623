#include "server/api/api_routes.hpp"

namespace tessera {

void add_api_routes(Router& router, ApiContext& context, const Readiness* readiness) {
  add_health_routes(router, readiness, context.api_token_required);
  add_job_routes(router, context);
  add_worker_routes(router, context);
  add_scene_routes(router, context);
  add_lease_routes(router, context);
  add_asset_routes(router, context);
  add_control_routes(router, context);
  add_metrics_route(router, context);
  add_event_routes(router, context);
  add_web_routes(router, context);
}

}  // namespace tessera
