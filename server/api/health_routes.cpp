#include "common/protocol/health.hpp"
#include "common/protocol/paths.hpp"
#include "server/api/api_json.hpp"
#include "server/api/api_routes.hpp"

namespace tessera {

void add_health_routes(Router& router, const Readiness* readiness, bool api_token_required) {
  router.add("GET", std::string(protocol::route::healthz),
             [api_token_required](HttpRequest&&, Respond respond) {
               respond(body_response(200, protocol::Health{api_token_required}));
             });
  // 503 both before start-up is over and once shutdown has begun: either way, requests
  // should go elsewhere (or wait), though the process is alive.
  router.add(
      "GET", std::string(protocol::route::readyz), [readiness](HttpRequest&&, Respond respond) {
        const Readiness::State state = readiness ? readiness->state() : Readiness::State::starting;
        if (state == Readiness::State::ready) return respond(body_response(200, protocol::Ready{}));
        if (state == Readiness::State::draining)
          return respond(error_response(503, "shutting_down", "the coordinator is shutting down"));
        respond(error_response(503, "starting", "the coordinator is still starting"));
      });
}

}  // namespace tessera
