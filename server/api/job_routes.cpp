#include <chrono>
#include <memory>
#include <optional>
#include <set>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "common/image/image_file_loader.hpp"
#include "common/image/image_io.hpp"
#include "common/mesh_files/folder_scene_files.hpp"
#include "common/protocol/image_format.hpp"
#include "common/protocol/paths.hpp"
#include "common/scene/frame_list.hpp"
#include "common/scene/scene_limits_scan.hpp"
#include "common/scene/scene_parser.hpp"
#include "common/scene/scene_stream.hpp"
#include "common/scene/texture_images.hpp"
#include "server/api/access.hpp"
#include "server/api/api_json.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/asset_store.hpp"
#include "server/api/submit_budget.hpp"

namespace tessera {
namespace {

using nlohmann::json;

HttpResponse not_found(const std::string& id) {
  return error_response(404, "not_found", "no job " + id);
}

// What reading a submission takes, per byte of its body, at most: the body, the scene's
// stored text and one object at a time in nodes (docs/performance.md, "Memory per
// submitted scene"). What a submission holds of the SubmitBudget.
constexpr std::size_t kSubmitBytesPerBodyByte = 4;
// After a body this large, the memory its reading freed goes back to the system.
constexpr std::size_t kTrimAfterBytes = 1 << 20;

// Given back to the system: the nodes of a scene are many small blocks, which glibc keeps
// in its arenas once freed, so that an idle coordinator would go on holding the memory of
// the largest scene it has read.
void return_free_memory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

// What a submission holds while it is read and stored: its share of the budget, and the
// memory to give back once it is done.
struct SubmissionMemory {
  explicit SubmissionMemory(bool large) : large(large) {}
  SubmissionMemory(const SubmissionMemory&) = delete;
  SubmissionMemory& operator=(const SubmissionMemory&) = delete;
  ~SubmissionMemory() {
    hold.reset();
    if (large) return_free_memory();
  }
  const bool large;
  std::optional<SubmitBudget::Hold> hold;
};

std::string mebibytes(std::size_t bytes) {
  return std::to_string((bytes + (1 << 20) - 1) >> 20) + " MiB";
}

HttpResponse busy(const SubmitBudget& budget, std::size_t needed) {
  HttpResponse response =
      error_response(503, "busy",
                     "the coordinator is reading other scenes, which hold " +
                         mebibytes(budget.held()) + " of its " + mebibytes(budget.limit()) +
                         " for them (--submit-memory-budget); this one needs " + mebibytes(needed) +
                         ": try again shortly");
  response.headers.emplace_back("Retry-After", "1");
  return response;
}

HttpResponse scene_refused(const SceneError& e) {
  const std::string path = "/scene" + e.pointer();
  if (e.limit().empty())
    return error_response(400, "invalid_scene", path + ": " + e.detail(), path);
  // Valid, but more than this server takes: say which limit, so the user can ask for it.
  return json_response(
      422, protocol::to_json(protocol::Error{"over_limit", path + ": " + e.detail(), path,
                                             e.limit(), e.limit_value()}));
}

// The frames a submission renders: those it names, or every frame of an animation's range;
// none for a still, which renders its one frame 0 (and may name it). A FrameListError says
// what is wrong, and where in the list.
std::vector<int> frames_of(const protocol::JobSubmission& submission, const Scene& scene,
                           const Limits& limits) {
  const Animation& animation = scene.animation;
  if (!animation.animated) {
    if (submission.frames) {
      try {
        parse_frame_list(*submission.frames, 0, 0, 1);
      } catch (const FrameListError& e) {
        throw FrameListError(std::string(e.what()) +
                             " (the scene has no \"animation\": a still is frame 0)");
      }
    }
    return {};
  }
  // The scene's range is within max_frames already (the parser's limit).
  if (!submission.frames) {
    std::vector<int> every;
    for (int frame = animation.first; frame <= animation.last; ++frame) every.push_back(frame);
    return every;
  }
  return parse_frame_list(*submission.frames, animation.first, animation.last, limits.max_frames);
}

// What the network's thread hands the blocking pool of a submission it has read.
struct Taken {
  protocol::JobSubmission submission;
  ObjectTexts objects;
};
void check_and_submit(ApiContext& context, Taken taken, std::shared_ptr<SubmissionMemory> memory,
                      Respond respond);

// The submission envelope around the scene (`JobSubmission`). Memory is bounded by the
// body, not amplified by it: a first pass builds nothing and refuses a scene over a count
// limit where it crosses it; only then are nodes made, and the scene's objects, by far its
// largest part, are read and checked one at a time (common/scene/scene_stream.hpp).
void submit(ApiContext& context, HttpRequest& request, Respond respond) {
  // Declared before the body, so that it gives memory back after the body is freed.
  auto memory = std::make_shared<SubmissionMemory>(request.body.size() >= kTrimAfterBytes);
  std::string body = std::move(request.body);
  // The budget's share goes back before the answer, so that a client that sends its next
  // submission as soon as it has this one's answer finds the share free.
  const auto answer = [&memory, &respond](HttpResponse response) {
    memory->hold.reset();
    respond(std::move(response));
  };
  if (context.submit_budget) {
    const std::size_t needed = body.size() * kSubmitBytesPerBodyByte;
    auto hold = context.submit_budget->try_hold(needed);
    if (!hold) return answer(busy(*context.submit_budget, needed));
    memory->hold.emplace(std::move(*hold));
  }
  ObjectTexts objects;
  json envelope;
  try {
    using protocol::JobSubmission;
    scan_scene_limits(body, context.limits, JobSubmission::kSceneKey);
    objects.reserve(body.size());  // room only: untouched, it costs nothing
    // Any key but JobSubmission's is refused by its name, and its value not built.
    envelope =
        parse_json_objects_apart(body, JobSubmission::kSceneKey, objects, JobSubmission::kKeys);
  } catch (const SceneError& e) {
    // A syntax error is not the scene's: the scan puts it at the document ("").
    if (e.pointer().empty()) return answer(error_response(400, "malformed_json", e.detail()));
    return answer(scene_refused(e));
  }
  std::string().swap(body);  // all of it is in `envelope` and `objects` now
  protocol::JobSubmission submission;
  try {
    submission = protocol::JobSubmission::take(envelope);
  } catch (const protocol::ProtocolError& e) {
    return answer(invalid_request(e));
  }
  // Off the network's threads: mesh files are read from the asset store to be checked.
  auto taken = std::make_shared<Taken>(Taken{std::move(submission), std::move(objects)});
  context.run_disk([&context, taken, memory, respond = std::move(respond)]() mutable {
    check_and_submit(context, std::move(*taken), memory, std::move(respond));
  });
}

// Each texture's header, read now so that an image no worker could decode, or a scene over
// the textures' limits, is refused at submit rather than failing every tile.
void check_textures(const Scene& scene) {
  const std::vector<TextureImage> images = texture_images(scene);
  if (images.empty()) return;
  try {
    image_files().check_textures(images);
  } catch (const std::runtime_error& e) {
    throw SceneError("/materials", e.what());
  }
}

void check_and_submit(ApiContext& context, Taken taken, std::shared_ptr<SubmissionMemory> memory,
                      Respond respond) {
  protocol::JobSubmission& submission = taken.submission;
  ObjectTexts& objects = taken.objects;
  const auto answer = [&memory, &respond](HttpResponse response) {
    memory->hold.reset();
    respond(std::move(response));
  };
  std::optional<AssetSceneFiles> files;
  if (context.assets) {
    files.emplace(
        [store = context.assets](const std::string& digest) { return store->reference(digest); });
  }
  Scene scene;
  try {
    scene = check_scene(submission.scene, context.limits, objects, files ? &*files : nullptr);
    check_textures(scene);
  } catch (const MissingAssetError& e) {
    const std::string path = "/scene" + e.pointer();
    return answer(error_response(422, "missing_asset", path + ": " + e.detail(), path));
  } catch (const SceneError& e) {
    return answer(scene_refused(e));
  }
  std::vector<int> frames;
  try {
    frames = frames_of(submission, scene, context.limits);
  } catch (const FrameListError& e) {
    return answer(
        error_response(400, "invalid_request", std::string("/frames: ") + e.what(), "/frames"));
  }
  // Each frame's tiles are kept in memory while the job lives, within the scheduler's
  // limits: of one job (--max-job-tiles), and of all of them (--job-memory-budget).
  // A still has no frame list: its one frame 0.
  const std::uint64_t frame_count = std::max<std::size_t>(1, frames.size());
  const std::uint64_t tiles =
      frame_count * tile_count(scene.width, scene.height, scene.render.tile_size);
  const std::string tiles_path = frames.size() > 1 ? "/frames" : "/scene/render/tile_size";
  const std::uint64_t max_tiles = context.scheduler.config().max_job_tiles;
  if (max_tiles > 0 && tiles > max_tiles)
    return answer(
        json_response(422, protocol::to_json(protocol::Error{
                               "over_limit",
                               tiles_path + ": " + std::to_string(frames.size()) + " frame(s) of " +
                                   std::to_string(tiles / std::max<std::size_t>(1, frames.size())) +
                                   " tiles each are " + std::to_string(tiles) +
                                   " tiles; a job holds at most " + std::to_string(max_tiles) +
                                   " (--max-job-tiles): fewer frames, or a larger tile_size",
                               tiles_path, "max_job_tiles", max_tiles})));
  if (const std::optional<std::string> refusal = context.scheduler.job_memory_refusal(tiles))
    return answer(json_response(
        422, protocol::to_json(protocol::Error{"over_limit", tiles_path + ": " + *refusal,
                                               tiles_path, "job_memory_budget",
                                               context.scheduler.config().job_memory_budget})));
  // The stored text is the scene's dump(), byte for byte: its digest is what workers ask
  // for, and the same scene sent twice is stored once.
  std::string scene_json = dump_scene(submission.scene, std::move(objects));
  submission.scene = json();
  context.scheduler.submit(
      submission.name, submission.priority, scene, std::move(scene_json),
      [&context, memory, respond = std::move(respond)](std::optional<JobRecord> job,
                                                       const std::string& error) {
        memory->hold.reset();  // before the answer, as above
        // The store refused (a full disk, say): nothing was created.
        if (!job) return respond(storage_failed("the job", error));
        HttpResponse response = body_response(201, status_of(*job, context.clock.now_ms()));
        response.headers.emplace_back("Location", protocol::fill(protocol::route::job, job->id));
        respond(std::move(response));
      },
      std::move(frames));
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
  const auto limit = query_count(request, protocol::query::limit, 1, 1000, 100);
  if (const auto* refused = std::get_if<HttpResponse>(&limit)) return *refused;
  const auto offset = query_count(request, protocol::query::offset, 0, 1'000'000'000, 0);
  if (const auto* refused = std::get_if<HttpResponse>(&offset)) return *refused;
  protocol::JobList list;
  const std::int64_t now = context.clock.now_ms();
  // The jobs whose id begins so: how a client finds the job a short id names.
  if (auto it = request.query.find(std::string(protocol::query::id_prefix));
      it != request.query.end()) {
    for (const std::string& id :
         context.scheduler.job_ids_with_prefix(it->second, std::get<std::size_t>(limit)))
      if (const auto job = context.scheduler.job(id); job && (!state || job->state == *state))
        list.jobs.push_back(status_of(*job, now));
    return body_response(200, list);
  }
  std::optional<std::string> name;
  if (auto it = request.query.find(std::string(protocol::query::name)); it != request.query.end())
    name = it->second;
  for (const JobRecord& job : context.scheduler.jobs(state, std::get<std::size_t>(limit),
                                                     std::get<std::size_t>(offset), name))
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

// The image of a job's frame: GET /v1/jobs/{id}/frames/{frame}/image, or (without a frame
// in the path) GET /v1/jobs/{id}/image, the first frame's, which for a still is its image.
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
  const auto named = request.params.find("frame");
  int frame = job->frames->numbers.front();
  if (named != request.params.end()) {
    const std::string& text = named->second;
    if (text.empty() || text.size() > 9 ||
        text.find_first_not_of("0123456789") != std::string::npos)
      return respond(error_response(400, "invalid_request",
                                    "frame must be a whole number from 0 to 999999999"));
    frame = std::stoi(text);
  }
  const std::optional<FrameRecord> info = context.scheduler.frame(id, frame);
  if (!info)
    return respond(error_response(
        404, "not_found",
        "job " + id + " renders no frame " + std::to_string(frame) + "; its frames are " +
            (job->frames->animated() ? job->frames->list : std::string("0"))));
  const bool done = info->state == protocol::FrameState::done;
  if (!done && partial != "1") {
    const std::string what =
        named == request.params.end() || !job->frames->animated()
            ? "job " + id + " is " + to_string(job->state)
            : "frame " + std::to_string(frame) + " of job " + id + " is " +
                  std::string(protocol::name_in(protocol::kFrameStateNames, info->state));
    return respond(
        error_response(409, "not_ready", what + "; add ?partial=1 for the tiles rendered so far"));
  }
  // A frame done has the EXR the image thread wrote: sent as it is, with no image
  // assembled in memory (3 GiB for a 16384x16384 frame).
  if (format->kind == ImageFileKind::exr && done) {
    if (const auto written = context.scheduler.frame_image_file(id, frame)) {
      HttpResponse response{200, std::string(format->content_type), "", {}};
      response.file = written->string();
      return respond(std::move(response));
    }
  }
  // Assembled from the canvas or, on the store thread, from the store; encoded where the
  // disk may be waited on.
  context.scheduler.assemble_frame(
      id, frame,
      [&context, id, format, transfer = job->output_transfer,
       respond = std::move(respond)](std::shared_ptr<const Image> assembled) {
        if (!assembled) return respond(not_found(id));
        context.run_blocking(
            [&context, id, format, transfer, respond, assembled = std::move(assembled)] {
              respond(encoded(context, id, *assembled, *format, transfer));
            });
      });
}

// GET /v1/jobs/{id}/frames.
void frame_list(ApiContext& context, const HttpRequest& request, Respond respond) {
  const std::string id = request.params.at("id");
  respond_durable(context.scheduler, std::move(respond), [&context, id] {
    const auto frames = context.scheduler.frames(id);
    if (!frames) return not_found(id);
    protocol::FrameList list;
    list.frames.reserve(frames->size());
    for (const FrameRecord& frame : *frames) list.frames.push_back(frame_status_of(frame));
    return body_response(200, list);
  });
}

}  // namespace

void add_job_routes(Router& router, ApiContext& context) {
  router.add(
      "POST", std::string(protocol::route::jobs),
      [&context](HttpRequest&& request, Respond respond) {
        submit(context, request, std::move(respond));
      },
      RouteOptions{}.with_body_limit(context.max_job_body_bytes).with_role(role_client));
  router.add(
      "GET", std::string(protocol::route::jobs),
      [&context](HttpRequest&& request, Respond respond) {
        respond_durable(
            context.scheduler, std::move(respond),
            [&context, request = std::move(request)] { return list(context, request); });
      },
      RouteOptions{}.with_role(role_client));
  router.add(
      "GET", std::string(protocol::route::job),
      [&context](HttpRequest&& request, Respond respond) {
        status(context, request, std::move(respond));
      },
      RouteOptions{}.with_role(role_client));
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
      RouteOptions{}.with_role(role_client));
  router.add(
      "GET", std::string(protocol::route::job_image),
      [&context](HttpRequest&& request, Respond respond) {
        image(context, request, std::move(respond));
      },
      RouteOptions{}.with_role(role_client));
  router.add(
      "GET", std::string(protocol::route::job_frame_image),
      [&context](HttpRequest&& request, Respond respond) {
        image(context, request, std::move(respond));
      },
      RouteOptions{}.with_role(role_client));
  router.add(
      "GET", std::string(protocol::route::job_frames),
      [&context](HttpRequest&& request, Respond respond) {
        frame_list(context, request, std::move(respond));
      },
      RouteOptions{}.with_role(role_client));
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
      RouteOptions{}.with_role(role_client));
}

}  // namespace tessera
