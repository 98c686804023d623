// From the scheduler's records to the typed bodies of common/protocol, and from a request's
// body to a typed one: the coordinator's side of docs/openapi.yaml.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"
#include "common/protocol/jobs.hpp"
#include "common/protocol/leases.hpp"
#include "common/protocol/workers.hpp"
#include "server/farm/scheduler.hpp"
#include "server/http/http_types.hpp"

namespace tessera {

// The request's JSON body, or the 400 malformed_json answer naming line and column.
std::variant<nlohmann::json, HttpResponse> json_body(const HttpRequest& request);

// A body that is not of the protocol's shape: 400 invalid_request at its pointer.
HttpResponse invalid_request(const protocol::ProtocolError& error);

// The request's body as T (T::read), or the 400 answer saying what is wrong and where.
template <typename T>
std::variant<T, HttpResponse> request_body(const HttpRequest& request) {
  auto parsed = json_body(request);
  if (auto* refused = std::get_if<HttpResponse>(&parsed)) return std::move(*refused);
  try {
    return T::read(protocol::FieldReader(std::get<nlohmann::json>(parsed)));
  } catch (const protocol::ProtocolError& e) {
    return invalid_request(e);
  }
}

// A long poll's ?wait_s= (0 to 60 seconds; `fallback` when absent), or nothing when it is
// not such a number.
// The query parameter `name` as a whole number from `min` to `max`, `fallback` when it is
// absent; or the 400 that says what it must be.
std::variant<std::size_t, HttpResponse> query_count(const HttpRequest& request,
                                                    std::string_view name, std::size_t min,
                                                    std::size_t max, std::size_t fallback);
std::optional<std::chrono::milliseconds> wait_of(const HttpRequest& request, double fallback_s);
HttpResponse bad_wait();

// The one mapping from each record to what the API shows of it.
protocol::JobStatus status_of(const JobRecord& job, std::int64_t now_ms);
protocol::FrameStatus frame_status_of(const FrameRecord& frame);
protocol::Worker worker_of(const WorkerRecord& worker);
protocol::Lease lease_of(const LeaseRecord& lease, std::int64_t now_ms);

template <typename T>
HttpResponse body_response(int status, const T& body) {
  return json_response(status, protocol::to_json(body));
}

// Gives the answer `make` makes from memory as it is now, once all it reports is durable
// (Scheduler::durable()). Should the store refuse a change meanwhile (its jobs then fail),
// the answer is made again, so that it shows the failure rather than what was refused.
void respond_durable(Scheduler& scheduler, Respond respond, std::function<HttpResponse()> make);

// 507 storage_failed: the store refused `what` (a full disk, say), and its job has failed.
HttpResponse storage_failed(const std::string& what, const std::string& error);

// For respond_when_stored(), the answer of a change that reports nothing: 204 once it is
// stored, 507 naming `what` when the store refused it.
inline auto no_content_when_stored(std::string what) {
  return [what = std::move(what)](std::monostate, const std::string& error) {
    return error.empty() ? HttpResponse{204, "", "", {}} : storage_failed(what, error);
  };
}

// Answers with `make(value, error)` once the scheduler says `pending` may be given, on the
// store thread: the network's thread goes on meanwhile. `error` is the store's refusal of
// the change, "" when it is durable.
template <typename T, typename Make>
void respond_when_stored(Scheduler& scheduler, Pending<T> pending, Respond respond, Make make) {
  scheduler.when_stored(
      pending.ticket, pending.wrote,
      [value = std::move(pending.value), respond = std::move(respond), make = std::move(make)](
          const std::string& error) mutable { respond(make(std::move(value), error)); });
}

}  // namespace tessera
