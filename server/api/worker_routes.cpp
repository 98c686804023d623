#include <memory>

#include "common/protocol/paths.hpp"
#include "common/protocol/workers.hpp"
#include "server/api/access.hpp"
#include "server/api/api_json.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/worker_identity.hpp"
#include "server/api/worker_limits.hpp"

namespace tessera {
namespace {

namespace route = protocol::route;

void register_worker(ApiContext& context, const HttpRequest& request, Respond respond) {
  auto parsed = json_body(request);
  if (auto* refused = std::get_if<HttpResponse>(&parsed)) return respond(std::move(*refused));
  protocol::WorkerRegistration registration;
  try {
    registration =
        protocol::WorkerRegistration::read(protocol::FieldReader(std::get<nlohmann::json>(parsed)));
  } catch (const protocol::ProtocolMismatch& e) {
    // A worker of another protocol version would misread what this coordinator states (or
    // state nothing, like the builds before version 2): refused here, plainly, rather than
    // meeting later as results refused one by one.
    return respond(error_response(409, "protocol_mismatch", e.message(), e.pointer()));
  } catch (const protocol::ProtocolError& e) {
    return respond(invalid_request(e));
  }
  // The peer's address without its port: "10.0.0.7:51234" -> "10.0.0.7".
  const std::string host = registration.host.value_or(
      request.remote_address.substr(0, request.remote_address.rfind(':')));
  // Given here once; the coordinator keeps only its digest.
  std::string secret = new_worker_secret();
  // Registered before the answer's callback takes the secret (arguments have no order).
  auto registered = context.scheduler.register_worker(
      registration.name, host, registration.threads.value_or(1), worker_secret_digest(secret));
  respond_when_stored(
      context.scheduler, std::move(registered), std::move(respond),
      [&context, secret = std::move(secret)](const WorkerRecord& worker, const std::string& error) {
        if (!error.empty()) return storage_failed("the worker", error);
        const SchedulerConfig& config = context.scheduler.config();
        return body_response(
            201, protocol::Registration{worker.id, secret, config.heartbeat_interval_ms / 1e3,
                                        config.lease_timeout_ms / 1e3, kWorkerProtocolVersion,
                                        protocol_limits(context)});
      });
}

void claim(ApiContext& context, const HttpRequest& request, Respond respond) {
  const std::string worker = request.params.at("id");
  if (!context.scheduler.worker_known(worker))
    return respond(
        error_response(404, "unknown_worker", "no worker " + worker + "; register again"));
  if (auto refused = check_worker(context.scheduler, request, worker))
    return respond(std::move(*refused));
  const auto max_tiles_or_none = max_tiles_of(context, request);
  if (!max_tiles_or_none) return respond(bad_max_tiles(context));
  const int max_tiles = *max_tiles_or_none;
  const auto wait = wait_of(request, 20);
  if (!wait) return respond(bad_wait());
  context.scheduler.touch_worker(worker);
  // Shared by the attempt and the timeout, which between them call it exactly once.
  auto shared_respond = std::make_shared<Respond>(std::move(respond));
  context.claims.wait(
      *wait,
      [&context, worker, max_tiles, shared_respond] {
        auto lease = context.scheduler.claim(worker, max_tiles);
        if (!lease.value) return false;
        respond_when_stored(
            context.scheduler, std::move(lease), *shared_respond,
            [&context](const std::optional<LeaseRecord>& granted, const std::string& error) {
              // The store refused the lease (a full disk, say); the job has failed and says why.
              if (!error.empty()) return storage_failed("the lease", error);
              return body_response(200, lease_of(*granted, context.clock.now_ms()));
            });
        return true;
      },
      [shared_respond] {
        (*shared_respond)(HttpResponse{204, "", "", {}});
      });
}

}  // namespace

void add_worker_routes(Router& router, ApiContext& context) {
  router.add(
      "GET", std::string(route::workers),
      [&context](HttpRequest&&, Respond respond) {
        respond_durable(context.scheduler, std::move(respond), [&context] {
          protocol::WorkerList list;
          for (const WorkerRecord& worker : context.scheduler.workers())
            list.workers.push_back(worker_of(worker));
          return body_response(200, list);
        });
      },
      RouteOptions{}.with_role(role_client));
  router.add(
      "POST", std::string(route::workers),
      [&context](HttpRequest&& request, Respond respond) {
        register_worker(context, request, std::move(respond));
      },
      RouteOptions{}.with_role(role_worker));
  router.add(
      "DELETE", std::string(route::worker),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        if (!context.scheduler.worker_known(id))
          return respond(error_response(404, "unknown_worker", "no worker " + id));
        if (auto refused = check_worker(context.scheduler, request, id))
          return respond(std::move(*refused));
        respond_when_stored(context.scheduler, context.scheduler.worker_left(id),
                            std::move(respond), no_content_when_stored("the departure"));
      },
      RouteOptions{}.with_role(role_worker));
  router.add(
      "POST", std::string(route::worker_claim),
      [&context](HttpRequest&& request, Respond respond) {
        claim(context, request, std::move(respond));
      },
      RouteOptions{}.with_role(role_worker));
}

}  // namespace tessera
