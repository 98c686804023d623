#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <variant>

#include <spdlog/spdlog.h>

#include "common/protocol/leases.hpp"
#include "common/protocol/paths.hpp"
#include "server/api/access.hpp"
#include "server/api/api_json.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/worker_identity.hpp"
#include "server/api/worker_limits.hpp"

namespace tessera {
namespace {

namespace route = protocol::route;

static_assert(std::endian::native == std::endian::little,
              "tile pixels travel as little-endian float32");

HttpResponse lease_lost(const std::string& id) {
  return error_response(
      410, "lease_lost",
      "lease " + id + " is no longer held: it expired, was reassigned or its job ended");
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

// An upload's tiles handed to the scheduler, or the answer that refuses it before.
using Checked = std::variant<Pending<ResultOutcome>, HttpResponse>;

// The offset of the first value that no render gives (NaN, an infinity, a negative), if any:
// such a value would poison every image and sum it is part of.
std::optional<std::size_t> first_impossible(std::span<const float> values) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!(values[i] >= 0.0f && values[i] <= std::numeric_limits<float>::max())) return i;
  return std::nullopt;
}

HttpResponse impossible_pixels(const std::string& where, std::size_t value, float seen) {
  const char* what = std::isnan(seen) ? "NaN" : std::isinf(seen) ? "an infinity" : "a negative";
  return error_response(400, "invalid_pixels",
                        where + " holds " + what + " at pixel " + std::to_string(value / 3) +
                            " (channel " + std::to_string(value % 3) +
                            "); a render gives finite values of 0 or more");
}

Checked check_upload(ApiContext& context, HttpRequest& request) {
  const std::string& id = request.params.at("id");
  if (request.body.size() % (3 * sizeof(float)) != 0)
    return error_response(400, "wrong_size", "the body must be whole float32 RGB pixels");
  // The request's headers are kept under lower-case names.
  const auto header = [&](std::string_view name) -> const std::string* {
    const auto it = request.headers.find(ascii_lower(name));
    return it == request.headers.end() ? nullptr : &it->second;
  };
  std::vector<std::uint64_t> rays{0};
  if (const std::string* text = header(protocol::kRaysHeader)) {
    const auto parsed = protocol::parse_number_list(*text);
    if (!parsed)
      return error_response(400, "invalid_request",
                            "X-Tessera-Rays must be whole numbers separated by commas");
    rays = *parsed;
  }
  std::vector<float> copy;
  const std::span<const float> pixels = floats_of(request.body, copy);

  if (const std::string* text = header(protocol::kTilesHeader)) {
    // Some of the lease's tiles, in the order given, each the size of its tile. Counted
    // before the list is parsed, so that an over-long one costs no more than its header.
    const ProtocolLimits limits = protocol_limits(context);
    const std::uint64_t named =
        static_cast<std::uint64_t>(std::count(text->begin(), text->end(), ',')) + 1;
    if (named > static_cast<std::uint64_t>(limits.max_result_tiles))
      return error_response(413, "too_many_tiles", result_tiles_over_limit(limits, named));
    const auto tiles = protocol::parse_number_list(*text);
    if (!tiles)
      return error_response(400, "invalid_request",
                            "X-Tessera-Tiles must be tile indexes separated by commas");
    if (rays.size() != tiles->size())
      return error_response(400, "invalid_request",
                            "X-Tessera-Rays must give one count per tile in X-Tessera-Tiles");
    const auto sizes = context.scheduler.tile_pixel_counts(id, *tiles);
    if (!sizes)
      return error_response(409, "lease_lost",
                            "lease " + id + " is no longer held; the result was refused");
    // An index past an int names no tile of any job: the lease refuses it as not its own.
    std::vector<int> indexes;
    for (const std::uint64_t index : *tiles)
      indexes.push_back(index > static_cast<std::uint64_t>(std::numeric_limits<int>::max())
                            ? -1
                            : static_cast<int>(index));
    auto results = slice_upload(pixels, indexes, *sizes, rays);
    if (!results) return Pending<ResultOutcome>{ResultOutcome::wrong_size};
    if (const std::string* text = header(protocol::kRenderMicrosecondsHeader)) {
      const auto times = protocol::parse_number_list(*text);
      if (!times || times->size() != results->size())
        return error_response(400, "invalid_request",
                              "X-Tessera-Render-Us must give one whole number of microseconds "
                              "per tile in X-Tessera-Tiles");
      for (std::size_t i = 0; i < results->size(); ++i) (*results)[i].render_us = (*times)[i];
    }
    for (const TileResult& tile : *results)
      if (const auto bad = first_impossible(tile.pixels))
        return impossible_pixels("tile " + std::to_string(tile.tile_index), *bad,
                                 tile.pixels[*bad]);
    return context.scheduler.complete(id, *results);
  }
  if (rays.size() != 1)
    return error_response(400, "invalid_request",
                          "X-Tessera-Rays must be one count when X-Tessera-Tiles is absent");
  if (const auto bad = first_impossible(pixels))
    return impossible_pixels("the upload", *bad, pixels[*bad]);
  return context.scheduler.complete(id, pixels, rays.front());
}

HttpResponse result_response(ResultOutcome outcome, const std::string& id) {
  switch (outcome) {
    case ResultOutcome::accepted:
      return body_response(200, protocol::ResultAnswer{protocol::ResultStatus::accepted});
    case ResultOutcome::duplicate:
      // Harmless to the image, but a healthy worker never renders a tile twice.
      spdlog::warn("duplicate result for lease {}: the tiles were already delivered", id);
      return body_response(200, protocol::ResultAnswer{protocol::ResultStatus::duplicate});
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
      return error_response(
          400, "wrong_tile",
          "a tile named in X-Tessera-Tiles is not this lease's, or is named twice");
  }
  return error_response(500, "internal", "unexpected result outcome");
}

// A result refused for any reason but a lost lease is a bug or a version mismatch on one
// side: shown on the job, not only in the worker's log.
void note_refusal(ApiContext& context, const std::string& id, const HttpResponse& response) {
  if (response.status < 400 || response.status >= 500 || response.status == 409) return;
  const std::string why = std::to_string(response.status) + ": " +
                          protocol::error_message(response.status, response.body);
  spdlog::warn("result for lease {} refused ({})", id, why);
  context.scheduler.note_refused_result(id, why);
}

// The request lives until the answer: its body holds the pixels the store thread writes.
void upload(ApiContext& context, std::shared_ptr<HttpRequest> request, Respond respond) {
  if (auto refused = check_lease_holder(context.scheduler, *request, request->params.at("id")))
    return respond(std::move(*refused));
  Checked checked = check_upload(context, *request);
  const std::string id = request->params.at("id");
  if (auto* refused = std::get_if<HttpResponse>(&checked)) {
    note_refusal(context, id, *refused);
    return respond(std::move(*refused));
  }
  respond_when_stored(
      context.scheduler, std::get<Pending<ResultOutcome>>(std::move(checked)), std::move(respond),
      [&context, id, request](ResultOutcome outcome, const std::string& error) {
        request->body = std::string();  // the pixels are stored: free them before answering
        HttpResponse response =
            result_response(error.empty() ? outcome : ResultOutcome::unstored, id);
        note_refusal(context, id, response);
        return response;
      });
}

// The worker could not render that tile of its lease (`TileFailure`).
void report_failure(ApiContext& context, const HttpRequest& request, Respond respond) {
  if (auto refused = check_lease_holder(context.scheduler, request, request.params.at("id")))
    return respond(std::move(*refused));
  auto failure = request_body<protocol::TileFailure>(request);
  if (auto* refused = std::get_if<HttpResponse>(&failure)) return respond(std::move(*refused));
  const auto& [tile, error] = std::get<protocol::TileFailure>(failure);
  respond_when_stored(context.scheduler,
                      context.scheduler.fail_tile(request.params.at("id"), tile, error),
                      std::move(respond), no_content_when_stored("the change"));
}

}  // namespace

void add_lease_routes(Router& router, ApiContext& context) {
  router.add(
      "POST", std::string(route::lease_heartbeat),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        if (auto refused = check_lease_holder(context.scheduler, request, id))
          return respond(std::move(*refused));
        auto lease = context.scheduler.heartbeat(id);
        if (lease.value) context.scheduler.touch_worker(lease.value->worker_id);
        respond_when_stored(
            context.scheduler, std::move(lease), std::move(respond),
            [&context, id](const std::optional<LeaseRecord>& renewed, const std::string&) {
              return renewed ? body_response(200, lease_of(*renewed, context.clock.now_ms()))
                             : lease_lost(id);
            });
      },
      RouteOptions{}.with_role(role_worker));
  router.add(
      "POST", std::string(route::lease_extend),
      [&context](HttpRequest&& request, Respond respond) {
        const std::string& id = request.params.at("id");
        if (auto refused = check_lease_holder(context.scheduler, request, id))
          return respond(std::move(*refused));
        const auto max_tiles = max_tiles_of(context, request);
        if (!max_tiles) return respond(bad_max_tiles(context));
        auto lease = context.scheduler.extend(id, *max_tiles);
        if (lease.value) context.scheduler.touch_worker(lease.value->worker_id);
        respond_when_stored(
            context.scheduler, std::move(lease), std::move(respond),
            [&context, id](const std::optional<LeaseRecord>& extended, const std::string& error) {
              // As for a claim: the store refused the new tiles, and the job has failed.
              if (!error.empty()) return storage_failed("the lease", error);
              return extended ? body_response(200, lease_of(*extended, context.clock.now_ms()))
                              : lease_lost(id);
            });
      },
      RouteOptions{}.with_role(role_worker));
  router.add(
      "PUT", std::string(route::lease_result),
      [&context](HttpRequest&& request, Respond respond) {
        upload(context, std::make_shared<HttpRequest>(std::move(request)), std::move(respond));
      },
      RouteOptions{}
          .with_body_limit(protocol_limits(context).max_result_bytes)
          .with_role(role_worker)
          .with_content_type(std::string(protocol::kPixelsContentType)));
  router.add(
      "POST", std::string(route::lease_fail),
      [&context](HttpRequest&& request, Respond respond) {
        report_failure(context, request, std::move(respond));
      },
      RouteOptions{}.with_role(role_worker));
  router.add(
      "POST", std::string(route::lease_release),
      [&context](HttpRequest&& request, Respond respond) {
        if (auto refused = check_lease_holder(context.scheduler, request, request.params.at("id")))
          return respond(std::move(*refused));
        respond_when_stored(context.scheduler, context.scheduler.release(request.params.at("id")),
                            std::move(respond), no_content_when_stored("the change"));
      },
      RouteOptions{}.with_role(role_worker));
}

}  // namespace tessera
