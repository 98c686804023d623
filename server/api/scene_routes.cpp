#include "common/protocol/paths.hpp"
#include "server/api/access.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/worker_identity.hpp"

namespace tessera {

void add_scene_routes(Router& router, ApiContext& context) {
  // The scene as submitted, for registered workers; they cache it by its digest.
  router.add(
      "GET", std::string(protocol::route::scene),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& digest = request.params.at("digest");
        if (auto refused = check_any_worker(context.scheduler, request))
          return respond(std::move(*refused));
        // Read on the store thread, and answered from there.
        context.scheduler.scene_json(
            digest, [digest, respond = std::move(respond)](std::optional<std::string> scene) {
              respond(scene ? HttpResponse{200, "application/json", std::move(*scene), {}}
                            : error_response(404, "not_found", "no scene " + digest));
            });
      },
      RouteOptions{}.with_role(role_worker));
}

}  // namespace tessera
