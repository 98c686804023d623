#include "common/protocol/paths.hpp"
#include "server/access.hpp"
#include "server/api_routes.hpp"

namespace tessera {

void add_scene_routes(Router& router, ApiContext& context) {
  // The scene as submitted; workers cache it by its digest.
  router.add(
      "GET", std::string(protocol::route::scene),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& digest = request.params.at("digest");
        const auto scene = context.scheduler.scene_json(digest);
        respond(scene ? HttpResponse{200, "application/json", *scene, {}}
                      : error_response(404, "not_found", "no scene " + digest));
      },
      std::nullopt, role_worker);
}

}  // namespace tessera
