// The farm's controls: a job's priority (PATCH /v1/jobs/{id}), pausing, resuming and
// retrying it, draining and removing workers. Each answers once its change is durable,
// with the job's or the worker's state as it is then.
#include "common/protocol/jobs.hpp"
#include "common/protocol/paths.hpp"
#include "server/api/access.hpp"
#include "server/api/api_json.hpp"
#include "server/api/api_routes.hpp"

namespace tessera {
namespace {

namespace route = protocol::route;

// The answer to a control of a job: its status once the change is durable, or why not.
auto job_answer(ApiContext& context, const std::string& id, std::string what) {
  return [&context, id, what = std::move(what)](const ControlOutcome& outcome,
                                                const std::string& error) {
    if (!error.empty()) return storage_failed(what + " of job " + id, error);
    if (outcome.result == ControlOutcome::Result::refused)
      return error_response(409, outcome.code, outcome.message);
    const auto job = context.scheduler.job(id);
    if (outcome.result == ControlOutcome::Result::not_found || !job)
      return error_response(404, "not_found", "no job " + id);
    return body_response(200, status_of(*job, context.clock.now_ms()));
  };
}

auto worker_answer(ApiContext& context, const std::string& id, std::string what) {
  return [&context, id, what = std::move(what)](const ControlOutcome& outcome,
                                                const std::string& error) {
    if (!error.empty()) return storage_failed(what + " of worker " + id, error);
    if (outcome.result == ControlOutcome::Result::not_found)
      return error_response(404, "unknown_worker", "no worker " + id);
    for (const WorkerRecord& worker : context.scheduler.workers())
      if (worker.id == id) return body_response(200, worker_of(worker));
    return error_response(404, "unknown_worker", "no worker " + id);
  };
}

// A POST route on a job that `control` changes.
void add_job_control(Router& router, ApiContext& context, std::string_view pattern,
                     Pending<ControlOutcome> (Scheduler::*control)(const std::string&),
                     const char* what) {
  router.add(
      "POST", std::string(pattern),
      [&context, control, what](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        respond_when_stored(context.scheduler, (context.scheduler.*control)(id), std::move(respond),
                            job_answer(context, id, what));
      },
      RouteOptions{}.with_role(role_client));
}

void add_drain(Router& router, ApiContext& context, std::string_view pattern, bool draining) {
  router.add(
      "POST", std::string(pattern),
      [&context, draining](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        respond_when_stored(
            context.scheduler, context.scheduler.drain_worker(id, draining), std::move(respond),
            worker_answer(context, id, draining ? "the draining" : "the undraining"));
      },
      RouteOptions{}.with_role(role_client));
}

}  // namespace

void add_control_routes(Router& router, ApiContext& context) {
  // A change is a few bytes; anything larger is not one.
  constexpr std::size_t kMaxChangeBytes = 4096;
  router.add(
      "PATCH", std::string(route::job),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        auto change = request_body<protocol::JobChange>(request);
        if (auto* refused = std::get_if<HttpResponse>(&change)) return respond(std::move(*refused));
        const protocol::JobChange& wanted = std::get<protocol::JobChange>(change);
        if (!wanted.priority) {
          // Nothing to change: the status as it is, like any read.
          if (!context.scheduler.job(id))
            return respond(error_response(404, "not_found", "no job " + id));
          return respond_durable(context.scheduler, std::move(respond), [&context, id] {
            const auto job = context.scheduler.job(id);
            if (!job) return error_response(404, "not_found", "no job " + id);
            return body_response(200, status_of(*job, context.clock.now_ms()));
          });
        }
        respond_when_stored(context.scheduler, context.scheduler.set_priority(id, *wanted.priority),
                            std::move(respond), job_answer(context, id, "the new priority"));
      },
      RouteOptions{}.with_body_limit(kMaxChangeBytes).with_role(role_client));
  add_job_control(router, context, route::job_pause, &Scheduler::pause, "the pause");
  add_job_control(router, context, route::job_resume, &Scheduler::resume, "the resumption");
  add_job_control(router, context, route::job_retry, &Scheduler::retry, "the retry");
  add_drain(router, context, route::worker_drain, true);
  add_drain(router, context, route::worker_undrain, false);
  router.add(
      "POST", std::string(route::worker_remove),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        respond_when_stored(context.scheduler, context.scheduler.remove_worker(id),
                            std::move(respond),
                            [id](const ControlOutcome& outcome, const std::string& error) {
                              if (!error.empty())
                                return storage_failed("the removal of worker " + id, error);
                              if (outcome.result == ControlOutcome::Result::not_found)
                                return error_response(404, "unknown_worker", "no worker " + id);
                              return HttpResponse{204, "", "", {}};
                            });
      },
      RouteOptions{}.with_role(role_client));
}

}  // namespace tessera
