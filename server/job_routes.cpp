#include <chrono>
#include <memory>

#include "common/image_format.hpp"
#include "common/image_io.hpp"
#include "common/protocol/paths.hpp"
#include "common/scene_parser.hpp"
#include "server/access.hpp"
#include "server/api_json.hpp"
#include "server/api_routes.hpp"

namespace tessera {
namespace {

using nlohmann::json;

HttpResponse not_found(const std::string& id) {
  return error_response(404, "not_found", "no job " + id);
}

// The submission envelope around the scene (`JobSubmission`).
void submit(ApiContext& context, const HttpRequest& request, Respond respond) {
  auto parsed = json_body(request);
  if (auto* refused = std::get_if<HttpResponse>(&parsed)) return respond(std::move(*refused));
  protocol::JobSubmission submission;
  try {
    submission = protocol::JobSubmission::take(std::get<json>(parsed));
  } catch (const protocol::ProtocolError& e) {
    return respond(invalid_request(e));
  }
  Scene scene;
  try {
    scene = parse_scene(submission.scene, context.limits);
  } catch (const SceneError& e) {
    const std::string path = "/scene" + e.pointer();
    if (e.limit().empty())
      return respond(error_response(400, "invalid_scene", path + ": " + e.detail(), path));
    // Valid, but more than this server takes: say which limit, so the user can ask for it.
    return respond(
        json_response(422, protocol::to_json(protocol::Error{"over_limit", path + ": " + e.detail(),
                                                             path, e.limit(), e.limit_value()})));
  }
  context.scheduler.submit(
      submission.name, submission.priority, scene, submission.scene.dump(),
      [&context, respond = std::move(respond)](std::optional<JobStatus> job,
                                               const std::string& error) {
        // The store refused (a full disk, say): nothing was created.
        if (!job) return respond(storage_failed("the job", error));
        HttpResponse response = body_response(201, status_of(*job, context.clock.now_ms()));
        response.headers.emplace_back("Location", protocol::fill(protocol::route::job, job->id));
        respond(std::move(response));
      });
}

HttpResponse list(ApiContext& context, const HttpRequest& request) {
  std::optional<JobState> state;
  if (auto it = request.query.find(std::string(protocol::query::state));
      it != request.query.end()) {
    state = job_state_from_string(it->second);
    if (!state)
      return error_response(400, "invalid_request",
                            "state must be " + protocol::names_of(protocol::kJobStateNames));
  }
  std::size_t limit = 100;
  if (auto it = request.query.find(std::string(protocol::query::limit));
      it != request.query.end()) {
    try {
      std::size_t used = 0;
      const long value = std::stol(it->second, &used);
      if (used != it->second.size() || value < 1 || value > 1000) throw std::out_of_range("");
      limit = static_cast<std::size_t>(value);
    } catch (const std::exception&) {
      return error_response(400, "invalid_request", "limit must be an integer from 1 to 1000");
    }
  }
  protocol::JobList list;
  const std::int64_t now = context.clock.now_ms();
  for (const JobStatus& job : context.scheduler.jobs(state, limit))
    list.jobs.push_back(status_of(job, now));
  return body_response(200, list);
}

// With ?wait_s=S the answer waits until the job has finished, for at most S seconds, and
// is the job's status either way: `tessera submit --wait` learns of the end at once.
void status(ApiContext& context, const HttpRequest& request, Respond respond) {
  const std::string id = request.params.at("id");
  const auto wait = wait_of(request, 0);
  if (!wait) return respond(bad_wait());
  if (!context.scheduler.job(id)) return respond(not_found(id));
  // Shared by the attempt and the timeout, which between them call it exactly once.
  auto shared_respond = std::make_shared<Respond>(std::move(respond));
  const auto answer = [&context, id, shared_respond](bool only_if_finished) {
    const auto job = context.scheduler.job(id);
    if (job && only_if_finished && !is_finished(job->state)) return false;
    respond_durable(context.scheduler, *shared_respond, [&context, id] {
      const auto now = context.scheduler.job(id);
      return now ? body_response(200, status_of(*now, context.clock.now_ms())) : not_found(id);
    });
    return true;
  };
  context.job_waits.wait(
      *wait, [answer] { return answer(true); }, [answer] { answer(false); });
}

// The image of a job as assembled, encoded into a private temporary file that is sent from
// the disk and removed once opened (OpenImageIO writes files).
HttpResponse encoded(ApiContext& context, const std::string& id, const Image& image,
                     const ImageFormat& format, OutputTransfer transfer) {
  std::filesystem::create_directories(context.temp_dir);
  const auto path = context.temp_dir / (id + "-" + std::to_string(context.temp_counter++) +
                                        std::string(format.extension));
  write_image(image, path, transfer);
  HttpResponse response{200, std::string(format.content_type), "", {}};
  response.file = path.string();
  response.file_is_temporary = true;
  return response;
}

void image(ApiContext& context, const HttpRequest& request, Respond respond) {
  const std::string& id = request.params.at("id");
  const auto query_value = [&](std::string_view key, const char* fallback) {
    auto it = request.query.find(std::string(key));
    return it == request.query.end() ? std::string(fallback) : it->second;
  };
  const ImageFormat* format = image_format_named(query_value(protocol::query::format, "png"));
  if (!format)
    return respond(
        error_response(400, "invalid_request", "format must be " + image_format_names()));
  const std::string partial = query_value(protocol::query::partial, "0");
  if (partial != "0" && partial != "1")
    return respond(error_response(400, "invalid_request", "partial must be 0 or 1"));
  const auto job = context.scheduler.job(id);
  if (!job) return respond(not_found(id));
  if (job->state != JobState::completed && partial != "1")
    return respond(error_response(409, "not_ready",
                                  "job " + id + " is " + to_string(job->state) +
                                      "; add ?partial=1 for the tiles rendered so far"));
  // A completed job's EXR is the file the image thread wrote: sent as it is, with no
  // image assembled in memory (3 GiB for a 16384x16384 frame).
  if (format->kind == ImageFileKind::exr && job->state == JobState::completed) {
    if (const auto written = context.scheduler.image_file(id)) {
      HttpResponse response{200, std::string(format->content_type), "", {}};
      response.file = written->string();
      return respond(std::move(response));
    }
  }
  // Assembled from the canvas or, on the store thread, from the store; encoded where the
  // disk may be waited on.
  context.scheduler.assemble(
      id, [&context, id, format, transfer = job->output_transfer,
           respond = std::move(respond)](std::shared_ptr<const Image> assembled) {
        if (!assembled) return respond(not_found(id));
        context.run_blocking(
            [&context, id, format, transfer, respond, assembled = std::move(assembled)] {
              respond(encoded(context, id, *assembled, *format, transfer));
            });
      });
}

}  // namespace

void add_job_routes(Router& router, ApiContext& context) {
  router.add(
      "POST", std::string(protocol::route::jobs),
      [&context](HttpRequest&& request, Respond respond) {
        submit(context, request, std::move(respond));
      },
      context.max_job_body_bytes, role_client);
  router.add(
      "GET", std::string(protocol::route::jobs),
      [&context](HttpRequest&& request, Respond respond) {
        respond_durable(
            context.scheduler, std::move(respond),
            [&context, request = std::move(request)] { return list(context, request); });
      },
      std::nullopt, role_client);
  router.add(
      "GET", std::string(protocol::route::job),
      [&context](HttpRequest&& request, Respond respond) {
        status(context, request, std::move(respond));
      },
      std::nullopt, role_client);
  router.add(
      "DELETE", std::string(protocol::route::job),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        respond_when_stored(context.scheduler, context.scheduler.remove(id), std::move(respond),
                            [id](RemoveOutcome outcome, const std::string& error) {
                              if (!error.empty())
                                return storage_failed("the removal of job " + id, error);
                              switch (outcome) {
                                case RemoveOutcome::removed:
                                  return HttpResponse{204, "", "", {}};
                                case RemoveOutcome::not_found:
                                  return not_found(id);
                                case RemoveOutcome::not_finished:
                                  break;
                              }
                              return error_response(
                                  409, "not_finished",
                                  "job " + id + " is still active; cancel it first");
                            });
      },
      std::nullopt, role_client);
  router.add(
      "GET", std::string(protocol::route::job_image),
      [&context](HttpRequest&& request, Respond respond) {
        image(context, request, std::move(respond));
      },
      std::nullopt, role_client);
  router.add(
      "POST", std::string(protocol::route::job_cancel),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        respond_when_stored(
            context.scheduler, context.scheduler.cancel(id), std::move(respond),
            [&context, id](CancelOutcome outcome, const std::string& error) {
              if (!error.empty()) return storage_failed("the cancellation of job " + id, error);
              const auto job = context.scheduler.job(id);
              switch (outcome) {
                case CancelOutcome::canceled:
                  if (job) return body_response(200, status_of(*job, context.clock.now_ms()));
                  [[fallthrough]];
                case CancelOutcome::not_found:
                  return not_found(id);
                case CancelOutcome::already_finished:
                  break;
              }
              return error_response(409, "already_finished", "job " + id + " has already finished");
            });
      },
      std::nullopt, role_client);
}

}  // namespace tessera
