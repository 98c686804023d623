#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <span>

#include <spdlog/spdlog.h>

#include "common/protocol_limits.hpp"
#include "common/scene_parser.hpp"
#include "server/access.hpp"
#include "server/api_json.hpp"
#include "server/api_routes.hpp"

namespace tessera {
namespace {

using nlohmann::json;

static_assert(std::endian::native == std::endian::little,
              "tile pixels travel as little-endian float32");

// What this coordinator's worker protocol allows, as stated at registration: one
// definition, common/protocol_limits.hpp, for the checks here and the worker's groups.
ProtocolLimits protocol_limits(const ApiContext& context) {
  ProtocolLimits limits = coordinator_limits(context.limits.max_tile_size);
  limits.max_lease_tiles = context.scheduler.config().max_lease_tiles;
  return limits;
}

// "3,17,4" -> {3, 17, 4}; nothing when the list is not whole numbers separated by commas.
std::optional<std::vector<std::uint64_t>> parse_number_list(const std::string& text) {
  std::vector<std::uint64_t> numbers;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    if (item.empty() || item.size() > 19 || item.find_first_not_of("0123456789") != std::string::npos)
      return std::nullopt;
    numbers.push_back(std::stoull(item));
    start = end + 1;
  }
  return numbers;
}

HttpResponse lease_lost(const std::string& id) {
  return error_response(410, "lease_lost",
                        "lease " + id + " is no longer held: it expired, was reassigned or its job ended");
}

HttpResponse register_worker(ApiContext& context, const HttpRequest& request) {
  auto parsed = json_body(request);
  if (auto* refused = std::get_if<HttpResponse>(&parsed)) return std::move(*refused);
  json& body = std::get<json>(parsed);
  if (!body.is_object() || !body.contains("name") || !body["name"].is_string())
    return error_response(400, "invalid_request", "name is required and must be a string", "/name");
  // The peer's address without its port: "10.0.0.7:51234" -> "10.0.0.7".
  std::string host = request.remote_address.substr(0, request.remote_address.rfind(':'));
  if (body.contains("host")) {
    if (!body["host"].is_string())
      return error_response(400, "invalid_request", "must be a string", "/host");
    host = body["host"].get<std::string>();
  }
  for (const auto& [key, value] : {std::pair{"/name", body["name"].get<std::string>()}, std::pair{"/host", host}})
    if (value.size() > max_name_bytes)
      return error_response(400, "invalid_request",
                            "must be at most " + std::to_string(max_name_bytes) + " bytes", key);
  int threads = 1;
  if (body.contains("threads")) {
    if (!body["threads"].is_number_integer() || body["threads"].get<int>() < 1)
      return error_response(400, "invalid_request", "must be a positive integer", "/threads");
    threads = body["threads"].get<int>();
  }
  // A worker of another protocol version would misread what this coordinator states (or
  // state nothing, like the builds before version 2): refused here, plainly, rather than
  // meeting later as results refused one by one.
  const auto version = body.find("protocol");
  if (version == body.end() || !version->is_number_integer() ||
      version->get<std::int64_t>() != kWorkerProtocolVersion)
    return error_response(
        409, "protocol_mismatch",
        "this coordinator speaks worker protocol " + std::to_string(kWorkerProtocolVersion) +
            "; the worker " +
            (version == body.end() ? std::string("states none (a build older than protocol 2)")
                                   : "speaks " + version->dump().substr(0, 40)) +
            ". Run the same Tessera release on the coordinator and its workers",
        "/protocol");
  const WorkerInfo worker =
      context.scheduler.register_worker(body["name"].get<std::string>(), host, threads);
  const SchedulerConfig& config = context.scheduler.config();
  return json_response(201, {{"id", worker.id},
                             {"heartbeat_interval_s", config.heartbeat_interval_ms / 1e3},
                             {"lease_timeout_s", config.lease_timeout_ms / 1e3},
                             {"protocol", kWorkerProtocolVersion},
                             {"limits", to_json(protocol_limits(context))}});
}

// The request's max_tiles (1 when absent), or nothing when it is out of range.
std::optional<int> max_tiles_of(const ApiContext& context, const HttpRequest& request) {
  const auto it = request.query.find("max_tiles");
  if (it == request.query.end()) return 1;
  const auto parsed = parse_number_list(it->second);
  if (!parsed || parsed->size() != 1 || parsed->front() < 1 ||
      parsed->front() > static_cast<std::uint64_t>(protocol_limits(context).max_batch_tiles))
    return std::nullopt;
  return static_cast<int>(parsed->front());
}

HttpResponse bad_max_tiles(const ApiContext& context) {
  return error_response(400, "invalid_request",
                        "max_tiles must be an integer from 1 to " +
                            std::to_string(protocol_limits(context).max_batch_tiles));
}

void claim(ApiContext& context, const HttpRequest& request, Respond respond) {
  const std::string worker = request.params.at("id");
  if (!context.scheduler.worker_known(worker))
    return respond(error_response(404, "unknown_worker", "no worker " + worker + "; register again"));
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
        std::optional<Lease> lease;
        try {
          lease = context.scheduler.claim(worker, max_tiles);
        } catch (const std::exception& e) {
          // The store refused the lease (a full disk, say); the job has failed and says why.
          // Answered here, since a claim woken by notify() runs where nothing would catch it.
          (*shared_respond)(error_response(
              507, "storage_failed", std::string("cannot store the lease: ") + e.what()));
          return true;
        }
        if (!lease) return false;
        (*shared_respond)(json_response(200, to_json(*lease, context.clock.now_ms())));
        return true;
      },
      [shared_respond] { (*shared_respond)(HttpResponse{204, "", "", {}}); });
}

// The body's bytes as float32 pixels, in place: a copy of every upload would double the
// memory that the uploads of a thousand workers take while they queue. memmove onto
// itself starts the floats' lifetime (what C++23's std::start_lifetime_as says outright);
// a body that happens not to be aligned for float is copied into `copy` instead.
std::span<const float> floats_of(std::string& body, std::vector<float>& copy) {
  const std::size_t count = body.size() / sizeof(float);
  if (count == 0) return {};
  if (reinterpret_cast<std::uintptr_t>(body.data()) % alignof(float) != 0) {
    copy.resize(count);
    std::memcpy(copy.data(), body.data(), count * sizeof(float));
    return copy;
  }
  return {static_cast<const float*>(std::memmove(body.data(), body.data(), count * sizeof(float))),
          count};
}

HttpResponse check_upload(ApiContext& context, HttpRequest& request) {
  const std::string& id = request.params.at("id");
  if (request.body.size() % (3 * sizeof(float)) != 0)
    return error_response(400, "wrong_size", "the body must be whole float32 RGB pixels");
  const auto header = [&](const char* name) -> const std::string* {
    const auto it = request.headers.find(name);
    return it == request.headers.end() ? nullptr : &it->second;
  };
  std::vector<std::uint64_t> rays{0};
  if (const std::string* text = header("x-tessera-rays")) {
    const auto parsed = parse_number_list(*text);
    if (!parsed)
      return error_response(400, "invalid_request",
                            "X-Tessera-Rays must be whole numbers separated by commas");
    rays = *parsed;
  }
  std::vector<float> copy;
  const std::span<const float> pixels = floats_of(request.body, copy);

  ResultOutcome outcome{};
  if (const std::string* text = header("x-tessera-tiles")) {
    // Some of the lease's tiles, in the order given, each the size of its tile. Counted
    // before the list is parsed, so that an over-long one costs no more than its header.
    const ProtocolLimits limits = protocol_limits(context);
    const std::uint64_t named =
        static_cast<std::uint64_t>(std::count(text->begin(), text->end(), ',')) + 1;
    if (named > static_cast<std::uint64_t>(limits.max_result_tiles))
      return error_response(413, "too_many_tiles", result_tiles_over_limit(limits, named));
    const auto tiles = parse_number_list(*text);
    if (!tiles)
      return error_response(400, "invalid_request",
                            "X-Tessera-Tiles must be tile indexes separated by commas");
    if (rays.size() != tiles->size())
      return error_response(400, "invalid_request",
                            "X-Tessera-Rays must give one count per tile in X-Tessera-Tiles");
    const auto sizes = context.scheduler.tile_pixel_counts(id, *tiles);
    if (!sizes)
      return error_response(409, "lease_lost", "lease " + id + " is no longer held; the result was refused");
    std::vector<TileResult> results;
    std::size_t offset = 0;
    for (std::size_t i = 0; i < tiles->size(); ++i) {
      const std::size_t floats = (*sizes)[i] * 3;
      if (offset + floats > pixels.size()) break;
      results.push_back({static_cast<int>((*tiles)[i]),
                         std::span<const float>(pixels).subspan(offset, floats), rays[i]});
      offset += floats;
    }
    outcome = results.size() != tiles->size() || offset != pixels.size()
                  ? ResultOutcome::wrong_size
                  : context.scheduler.complete(id, results);
  } else {
    if (rays.size() != 1)
      return error_response(400, "invalid_request",
                            "X-Tessera-Rays must be one count when X-Tessera-Tiles is absent");
    outcome = context.scheduler.complete(id, pixels, rays.front());
  }
  switch (outcome) {
    case ResultOutcome::accepted: return json_response(200, {{"status", "accepted"}});
    case ResultOutcome::duplicate:
      // Harmless to the image, but a healthy worker never renders a tile twice.
      spdlog::warn("duplicate result for lease {}: the tiles were already delivered", id);
      return json_response(200, {{"status", "duplicate"}});
    case ResultOutcome::stale:
      return error_response(409, "lease_lost",
                            "lease " + id + " is no longer held; the result was refused");
    case ResultOutcome::wrong_size:
      return error_response(400, "wrong_size", "the pixel count does not match the tiles");
    case ResultOutcome::unstored:
      return error_response(507, "storage_failed",
                            "the coordinator could not store the result (is its disk full?), so "
                            "the job has failed; its status says why");
    case ResultOutcome::wrong_tile:
      return error_response(400, "wrong_tile",
                            "a tile named in X-Tessera-Tiles is not this lease's, or is named twice");
  }
  return error_response(500, "internal", "unexpected result outcome");
}

// A result refused for any reason but a lost lease is a bug or a version mismatch on one
// side: shown on the job, not only in the worker's log.
HttpResponse upload(ApiContext& context, HttpRequest& request) {
  HttpResponse response = check_upload(context, request);
  if (response.status >= 400 && response.status < 500 && response.status != 409) {
    const std::string& id = request.params.at("id");
    std::string why = std::to_string(response.status);
    try {
      why += ": " + json::parse(response.body).at("error").at("message").get<std::string>();
    } catch (const std::exception&) {
    }
    spdlog::warn("result for lease {} refused ({})", id, why);
    context.scheduler.note_refused_result(id, why);
  }
  return response;
}

// {"tile": 17, "error": "..."}: the worker could not render that tile of its lease.
HttpResponse report_failure(ApiContext& context, const HttpRequest& request) {
  auto parsed = json_body(request);
  if (auto* refused = std::get_if<HttpResponse>(&parsed)) return std::move(*refused);
  json& body = std::get<json>(parsed);
  if (!body.is_object() || !body.contains("tile") || !body["tile"].is_number_integer())
    return error_response(400, "invalid_request", "tile is required and must be an integer", "/tile");
  if (!body.contains("error") || !body["error"].is_string())
    return error_response(400, "invalid_request", "error is required and must be a string", "/error");
  // Kept short: it ends up in the job's error and in logs.
  std::string error = body["error"].get<std::string>().substr(0, 1000);
  context.scheduler.fail_tile(request.params.at("id"), body["tile"].get<int>(), error);
  return HttpResponse{204, "", "", {}};
}

}  // namespace

void add_worker_routes(Router& router, ApiContext& context) {
  router.add("GET", "/v1/workers", [&context](HttpRequest&&, Respond respond) {
    json workers = json::array();
    for (const WorkerInfo& worker : context.scheduler.workers()) workers.push_back(to_json(worker));
    respond(json_response(200, {{"workers", std::move(workers)}}));
  }, std::nullopt, role_client);
  router.add("POST", "/v1/workers", [&context](HttpRequest&& request, Respond respond) {
    respond(register_worker(context, request));
  }, std::nullopt, role_worker);
  router.add("DELETE", "/v1/workers/{id}", [&context](HttpRequest&& request, Respond respond) {
    const std::string& id = request.params.at("id");
    if (!context.scheduler.worker_known(id))
      return respond(error_response(404, "unknown_worker", "no worker " + id));
    context.scheduler.worker_left(id);
    respond(HttpResponse{204, "", "", {}});
  }, std::nullopt, role_worker);
  router.add("POST", "/v1/workers/{id}/claim", [&context](HttpRequest&& request, Respond respond) {
    claim(context, request, std::move(respond));
  }, std::nullopt, role_worker);
  router.add("GET", "/v1/scenes/{digest}", [&context](HttpRequest&& request, Respond respond) {
    const std::string& digest = request.params.at("digest");
    const auto scene = context.scheduler.scene_json(digest);
    respond(scene ? HttpResponse{200, "application/json", *scene, {}}
                  : error_response(404, "not_found", "no scene " + digest));
  }, std::nullopt, role_worker);
  router.add("POST", "/v1/leases/{id}/heartbeat", [&context](HttpRequest&& request, Respond respond) {
    const std::string& id = request.params.at("id");
    const auto lease = context.scheduler.heartbeat(id);
    if (lease) context.scheduler.touch_worker(lease->worker_id);
    respond(lease ? json_response(200, to_json(*lease, context.clock.now_ms())) : lease_lost(id));
  }, std::nullopt, role_worker);
  router.add("POST", "/v1/leases/{id}/extend", [&context](HttpRequest&& request, Respond respond) {
    const std::string& id = request.params.at("id");
    const auto max_tiles = max_tiles_of(context, request);
    if (!max_tiles) return respond(bad_max_tiles(context));
    std::optional<Lease> lease;
    try {
      lease = context.scheduler.extend(id, *max_tiles);
    } catch (const std::exception& e) {
      // As for a claim: the store refused the new tiles, and the job has failed.
      return respond(error_response(507, "storage_failed",
                                    std::string("cannot store the lease: ") + e.what()));
    }
    if (lease) context.scheduler.touch_worker(lease->worker_id);
    respond(lease ? json_response(200, to_json(*lease, context.clock.now_ms())) : lease_lost(id));
  }, std::nullopt, role_worker);
  router.add(
      "PUT", "/v1/leases/{id}/result",
      [&context](HttpRequest&& request, Respond respond) {
        HttpResponse response = upload(context, request);
        request.body = std::string();  // the pixels are stored: free them before answering
        respond(std::move(response));
      },
      protocol_limits(context).max_result_bytes, role_worker);
  router.add("POST", "/v1/leases/{id}/fail", [&context](HttpRequest&& request, Respond respond) {
    respond(report_failure(context, request));
  }, std::nullopt, role_worker);
  router.add("POST", "/v1/leases/{id}/release", [&context](HttpRequest&& request, Respond respond) {
    context.scheduler.release(request.params.at("id"));
    respond(HttpResponse{204, "", "", {}});
  }, std::nullopt, role_worker);
}

}  // namespace tessera
