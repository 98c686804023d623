#include "common/net/coordinator_client.hpp"

#include <algorithm>
#include <charconv>
#include <thread>

#include "common/protocol/asset_digest.hpp"
#include "common/protocol/assets.hpp"
#include "common/protocol/events.hpp"
#include "common/protocol/paths.hpp"

namespace tessera {

namespace route = protocol::route;
using protocol::fill;
using protocol::read_body;

CoordinatorClient::CoordinatorClient(const std::string& server_url, const std::string& token,
                                     std::chrono::milliseconds timeout, const TlsSettings& tls)
    : http_(server_url, timeout, tls) {
  http_.set_bearer_token(token);
}

namespace {

// The answer, when its status is 2xx or one of `accepted`; otherwise ApiError. A redirect
// is an error too: a coordinator never sends one, so the URL names something else.
HttpResult checked(HttpResult result, std::initializer_list<int> accepted = {}) {
  if (result.status >= 200 && result.status < 300) return result;
  for (const int status : accepted)
    if (result.status == status) return result;
  if (result.status >= 300 && result.status < 400) {
    const auto location = result.headers.find("location");
    throw ApiError(result.status,
                   {"",
                    "the server answered HTTP " + std::to_string(result.status) + " (a redirect" +
                        (location == result.headers.end() ? "" : " to " + location->second) +
                        "), which a coordinator never sends: is --server its URL?",
                    {},
                    {},
                    {}});
  }
  if (auto error = protocol::error_of(result.body))
    throw ApiError(result.status, std::move(*error));
  throw ApiError(result.status,
                 {"", protocol::error_message(result.status, result.body), {}, {}, {}});
}

}  // namespace

HttpResult CoordinatorClient::call(std::string_view method, const std::string& target,
                                   std::string body, std::initializer_list<int> accepted) {
  return checked(http_.request(method, target, std::move(body), "application/json", identity()),
                 accepted);
}

void CoordinatorClient::prove_as(std::string secret) {
  std::lock_guard lock(secret_mutex_);
  worker_secret_ = std::move(secret);
}

HttpClient::Headers CoordinatorClient::identity() const {
  std::lock_guard lock(secret_mutex_);
  if (worker_secret_.empty()) return {};
  return {{std::string(protocol::kWorkerSecretHeader), worker_secret_}};
}

protocol::JobStatus CoordinatorClient::submit(const protocol::JobSubmission& submission) {
  const std::string body = protocol::to_json(submission).dump();
  // A coordinator busy reading other large submissions (503 busy) kept nothing of this one:
  // it goes again after the Retry-After the answer gives, for about a minute at most.
  for (int attempt = 1;; ++attempt) {
    HttpResult result =
        http_.request("POST", std::string(route::jobs), body, "application/json", identity());
    const auto error = result.status == 503 ? protocol::error_of(result.body) : std::nullopt;
    if (!error || error->code != "busy" || attempt == kSubmitAttempts)
      return read_body<protocol::JobStatus>(checked(std::move(result)).body);
    std::chrono::seconds wait{1};
    if (const auto after = result.headers.find("retry-after"); after != result.headers.end()) {
      int seconds = 0;
      const auto [end, ec] = std::from_chars(after->second.data(),
                                             after->second.data() + after->second.size(), seconds);
      if (ec == std::errc() && seconds >= 0) wait = std::chrono::seconds(std::min(seconds, 10));
    }
    std::this_thread::sleep_for(wait);
  }
}

protocol::JobStatus CoordinatorClient::job(std::string_view id, double wait_s) {
  return read_body<protocol::JobStatus>(call("GET", protocol::job_target(id, wait_s)).body);
}

protocol::JobList CoordinatorClient::jobs(std::optional<JobState> state, int limit) {
  return read_body<protocol::JobList>(call("GET", protocol::jobs_target(state, limit)).body);
}

protocol::JobStatus CoordinatorClient::cancel(std::string_view id) {
  return read_body<protocol::JobStatus>(call("POST", fill(route::job_cancel, id)).body);
}

void CoordinatorClient::remove(std::string_view id) { call("DELETE", fill(route::job, id)); }

void CoordinatorClient::events(const std::string& target,
                               const std::optional<std::string>& last_event_id,
                               const std::function<bool()>& on_open,
                               const std::function<bool(const ServerEvent&)>& on_event) {
  HttpClient::Headers headers = identity();
  if (last_event_id) headers.emplace_back(protocol::kLastEventIdHeader, *last_event_id);
  bool opened = false;
  EventStreamParser parser(on_event);
  HttpResult result = http_.stream(
      target,
      [&](std::string_view piece) {
        // The stream begins with a comment, so that it is known to be open at once.
        if (!opened) {
          opened = true;
          if (!on_open()) return false;
        }
        return parser.feed(piece);
      },
      headers);
  checked(std::move(result));
}

protocol::JobStatus CoordinatorClient::change(std::string_view id,
                                              const protocol::JobChange& change) {
  return read_body<protocol::JobStatus>(
      call("PATCH", fill(route::job, id), protocol::to_json(change).dump()).body);
}

protocol::JobStatus CoordinatorClient::pause(std::string_view id) {
  return read_body<protocol::JobStatus>(call("POST", fill(route::job_pause, id)).body);
}

protocol::JobStatus CoordinatorClient::resume(std::string_view id) {
  return read_body<protocol::JobStatus>(call("POST", fill(route::job_resume, id)).body);
}

protocol::JobStatus CoordinatorClient::retry(std::string_view id) {
  return read_body<protocol::JobStatus>(call("POST", fill(route::job_retry, id)).body);
}

protocol::JobList CoordinatorClient::jobs_with_prefix(std::string_view prefix, int limit) {
  return read_body<protocol::JobList>(
      call("GET", protocol::jobs_with_prefix_target(prefix, limit)).body);
}

protocol::JobList CoordinatorClient::jobs_named(std::string_view name, int limit) {
  return read_body<protocol::JobList>(call("GET", protocol::jobs_named_target(name, limit)).body);
}

protocol::Worker CoordinatorClient::drain(std::string_view worker_id, bool draining) {
  return read_body<protocol::Worker>(
      call("POST", fill(draining ? route::worker_drain : route::worker_undrain, worker_id)).body);
}

void CoordinatorClient::remove_worker(std::string_view worker_id) {
  call("POST", fill(route::worker_remove, worker_id));
}

namespace {

// An image's body, once its type is the format's: a proxy's page answered with 200 must
// not be saved as the image.
std::string image_body(HttpResult result, const ImageFormat& format) {
  const auto type = result.headers.find("content-type");
  if (type == result.headers.end() || !type->second.starts_with(format.content_type))
    throw protocol::ProtocolError(
        "", "the answer is " +
                (type == result.headers.end() ? std::string("untyped") : type->second) + ", not " +
                std::string(format.content_type));
  return std::move(result.body);
}

}  // namespace

std::string CoordinatorClient::image(std::string_view id, const ImageFormat& format, bool partial) {
  return image_body(call("GET", protocol::image_target(id, format, partial)), format);
}

protocol::FrameList CoordinatorClient::frames(std::string_view id) {
  return read_body<protocol::FrameList>(call("GET", fill(route::job_frames, id)).body);
}

std::string CoordinatorClient::frame_image(std::string_view id, int frame,
                                           const ImageFormat& format, bool partial) {
  return image_body(call("GET", protocol::frame_image_target(id, frame, format, partial)), format);
}

protocol::WorkerList CoordinatorClient::workers() {
  return read_body<protocol::WorkerList>(call("GET", std::string(route::workers)).body);
}

protocol::Health CoordinatorClient::health() {
  return read_body<protocol::Health>(call("GET", std::string(route::healthz)).body);
}

protocol::Registration CoordinatorClient::register_worker(
    const protocol::WorkerRegistration& registration) {
  auto answer = read_body<protocol::Registration>(
      call("POST", std::string(route::workers), protocol::to_json(registration).dump()).body);
  prove_as(answer.secret);
  return answer;
}

std::optional<protocol::Lease> CoordinatorClient::claim(std::string_view worker, double wait_s,
                                                        int max_tiles) {
  const HttpResult result = call("POST", protocol::claim_target(worker, wait_s, max_tiles));
  if (result.status == 204) return std::nullopt;
  return read_body<protocol::Lease>(result.body);
}

std::optional<protocol::Lease> CoordinatorClient::heartbeat(std::string_view lease) {
  const HttpResult result = call("POST", fill(route::lease_heartbeat, lease), {}, {410});
  if (result.status == 410) return std::nullopt;
  return read_body<protocol::Lease>(result.body);
}

std::optional<protocol::Lease> CoordinatorClient::extend(std::string_view lease, int max_tiles) {
  const HttpResult result = call("POST", protocol::extend_target(lease, max_tiles), {}, {410});
  if (result.status == 410) return std::nullopt;
  return read_body<protocol::Lease>(result.body);
}

bool CoordinatorClient::has_asset(std::string_view sha256) {
  return call("HEAD", fill(route::asset, protocol::AssetDigest::of_hex(sha256).text()), {}, {404})
             .status == 200;
}

bool CoordinatorClient::put_asset(std::string_view sha256, std::string bytes) {
  const HttpResult result =
      checked(http_.request("PUT", fill(route::asset, protocol::AssetDigest::of_hex(sha256).text()),
                            std::move(bytes), "application/octet-stream"));
  return result.status == 201;
}

bool CoordinatorClient::put_asset_file(std::string_view sha256, const std::filesystem::path& path,
                                       const HttpClient::UploadProgress& progress) {
  const HttpResult result = checked(
      http_.send_file("PUT", fill(route::asset, protocol::AssetDigest::of_hex(sha256).text()), path,
                      "application/octet-stream", progress, identity()));
  return result.status == 201;
}

void CoordinatorClient::scene_asset_to(std::string_view sha256, const std::filesystem::path& into) {
  checked(http_.receive_file("GET",
                             fill(route::scene_asset, protocol::AssetDigest::of_hex(sha256).text()),
                             into, identity()));
}

std::string CoordinatorClient::scene(std::string_view digest) {
  return call("GET", fill(route::scene, digest)).body;
}

protocol::ResultAnswer CoordinatorClient::upload(std::string_view lease,
                                                 std::span<const std::uint64_t> tiles,
                                                 std::span<const std::uint64_t> rays,
                                                 std::string pixels,
                                                 std::span<const std::uint64_t> render_us) {
  HttpClient::Headers headers = identity();
  headers.emplace_back(protocol::kTilesHeader, protocol::number_list(tiles));
  headers.emplace_back(protocol::kRaysHeader, protocol::number_list(rays));
  if (!render_us.empty())
    headers.emplace_back(protocol::kRenderMicrosecondsHeader, protocol::number_list(render_us));
  return read_body<protocol::ResultAnswer>(
      checked(http_.request("PUT", fill(route::lease_result, lease), std::move(pixels),
                            protocol::kPixelsContentType, headers))
          .body);
}

void CoordinatorClient::fail(std::string_view lease, const protocol::TileFailure& failure) {
  call("POST", fill(route::lease_fail, lease), protocol::to_json(failure).dump());
}

void CoordinatorClient::release(std::string_view lease) {
  call("POST", fill(route::lease_release, lease));
}

void CoordinatorClient::leave(std::string_view worker) {
  call("DELETE", fill(route::worker, worker));
}

}  // namespace tessera
