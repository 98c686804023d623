// Server-sent events (GET /v1/events, GET /v1/jobs/{id}/events) and a job's tiles
// (GET /v1/jobs/{id}/tiles), which a page loads once and then follows by events.
#include "common/protocol/events.hpp"
#include "common/protocol/paths.hpp"
#include "server/api/access.hpp"
#include "server/api/api_json.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/event_hub.hpp"
#include "server/api/farm_events.hpp"

namespace tessera {
namespace {

namespace route = protocol::route;

std::optional<std::string> last_event_id(const HttpRequest& request) {
  const auto it = request.headers.find(ascii_lower(protocol::kLastEventIdHeader));
  if (it == request.headers.end()) return std::nullopt;
  return it->second;
}

HttpResponse event_stream(std::shared_ptr<Subscription> subscription) {
  HttpResponse response{200,
                        "text/event-stream",
                        "",
                        {{"Cache-Control", "no-store"},
                         // Proxies that buffer answers (nginx) would hold events back.
                         {"X-Accel-Buffering", "no"}}};
  response.stream = std::move(subscription);
  return response;
}

}  // namespace

void add_event_routes(Router& router, ApiContext& context) {
  router.add(
      "GET", std::string(route::events),
      [&context](HttpRequest&& request, Respond respond) {
        if (!context.events) return respond(error_response(404, "not_found", "no events here"));
        respond(event_stream(context.events->subscribe("", last_event_id(request))));
      },
      RouteOptions{}.with_role(role_client));
  router.add(
      "GET", std::string(route::job_events),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        if (!context.events || !context.scheduler.job(id))
          return respond(error_response(404, "not_found", "no job " + id));
        respond(event_stream(context.events->subscribe(id, last_event_id(request))));
      },
      RouteOptions{}.with_role(role_client));
  router.add(
      "GET", std::string(route::job_tiles),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        // A page at a time, so that a job of millions of tiles is never one answer of
        // hundreds of megabytes.
        const auto offset = query_count(request, protocol::query::offset, 0, 1'000'000'000, 0);
        if (const auto* refused = std::get_if<HttpResponse>(&offset)) return respond(*refused);
        const auto limit = query_count(request, protocol::query::limit, 1, protocol::kMaxTilesPage,
                                       protocol::kMaxTilesPage);
        if (const auto* refused = std::get_if<HttpResponse>(&limit)) return respond(*refused);
        respond_durable(context.scheduler, std::move(respond),
                        [&context, id, offset = std::get<std::size_t>(offset),
                         limit = std::get<std::size_t>(limit)] {
                          std::size_t total = 0;
                          const auto tiles = context.scheduler.tiles(id, offset, limit, total);
                          if (!tiles) return error_response(404, "not_found", "no job " + id);
                          protocol::TileList list;
                          list.tiles.reserve(tiles->size());
                          for (const FarmObserver::TileChange& tile : *tiles)
                            list.tiles.push_back(tile_status(tile));
                          list.total = static_cast<std::int64_t>(total);
                          const std::size_t next = std::min(offset, total) + tiles->size();
                          if (next < total) list.next_offset = static_cast<std::int64_t>(next);
                          return body_response(200, list);
                        });
      },
      RouteOptions{}.with_role(role_client));
}

}  // namespace tessera
