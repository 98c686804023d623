// The coordinator's API (docs/openapi.yaml) from the other side: every route of the CLI
// and of a worker, with the typed bodies of common/protocol. Safe to share between threads
// (HttpClient is), though a worker keeps one per concern: claims, its lease's heartbeat,
// uploads.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <mutex>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "common/net/event_stream.hpp"
#include "common/net/http_client.hpp"
#include "common/protocol/error.hpp"
#include "common/protocol/health.hpp"
#include "common/protocol/image_format.hpp"
#include "common/protocol/jobs.hpp"
#include "common/protocol/leases.hpp"
#include "common/protocol/workers.hpp"

namespace tessera {

// An error answer of the API: its status and its `Error` body.
class ApiError : public std::runtime_error {
 public:
  ApiError(int status, protocol::Error error)
      : std::runtime_error(error.message), status_(status), error_(std::move(error)) {}
  int status() const { return status_; }
  const std::string& code() const { return error_.code; }
  std::string path() const { return error_.path.value_or(""); }
  const protocol::Error& error() const { return error_; }
  // A proxy's 502, 503 or 504, with no coordinator's error in it: the coordinator behind
  // it is out of reach, as good as no answer.
  bool from_gateway() const {
    return error_.code.empty() && (status_ == 502 || status_ == 503 || status_ == 504);
  }

 private:
  int status_;
  protocol::Error error_;
};

class CoordinatorClient {
 public:
  // `token`: the API or worker token to send, "" for none. Throws std::invalid_argument
  // for a bad URL, std::runtime_error for a CA file that cannot be read.
  CoordinatorClient(const std::string& server_url, const std::string& token,
                    std::chrono::milliseconds timeout = std::chrono::seconds(60),
                    const TlsSettings& tls = {});

  // Each throws ApiError for an error answer (but those named), HttpError for none, and
  // protocol::ProtocolError for an answer not of the protocol's shape.

  // The client's routes. A submission answered 503 busy goes again after its Retry-After,
  // up to kSubmitAttempts times in all.
  static constexpr int kSubmitAttempts = 30;
  protocol::JobStatus submit(const protocol::JobSubmission& submission);
  // With `wait_s` > 0 the server answers once the job has finished, or after wait_s.
  protocol::JobStatus job(std::string_view id, double wait_s = 0);
  protocol::JobList jobs(std::optional<JobState> state, int limit);
  protocol::JobStatus cancel(std::string_view id);
  void remove(std::string_view id);
  // The farm's controls.
  protocol::JobStatus change(std::string_view id, const protocol::JobChange& change);
  protocol::JobStatus pause(std::string_view id);
  protocol::JobStatus resume(std::string_view id);
  protocol::JobStatus retry(std::string_view id);
  // The jobs whose id begins with `prefix`.
  protocol::JobList jobs_with_prefix(std::string_view prefix, int limit);
  protocol::JobList jobs_named(std::string_view name, int limit);
  protocol::Worker drain(std::string_view worker_id, bool draining);
  void remove_worker(std::string_view worker_id);
  std::string image(std::string_view id, const ImageFormat& format, bool partial);
  // Every frame of the job, and one frame's image (404 for a frame it does not render,
  // 409 not_ready for one not done unless `partial`).
  protocol::FrameList frames(std::string_view id);
  std::string frame_image(std::string_view id, int frame, const ImageFormat& format, bool partial);
  protocol::WorkerList workers();
  // Follows a stream of server-sent events (route::events, or a job's): `on_open` once it
  // is open, then `on_event` for each event, until either returns false (or the stream
  // ends: the coordinator stopped). `last_event_id` resumes a stream. Throws ApiError for
  // an error answer (404: no such job, or a coordinator without events), HttpError when
  // the stream breaks.
  void events(const std::string& target, const std::optional<std::string>& last_event_id,
              const std::function<bool()>& on_open,
              const std::function<bool(const ServerEvent&)>& on_event);
  protocol::Health health();  // GET /healthz
  // Assets by their SHA-256 (64 hex digits): whether the coordinator holds one (HEAD), and
  // an upload, true when it was new (201), false when already held (200).
  bool has_asset(std::string_view sha256);
  bool put_asset(std::string_view sha256, std::string bytes);
  // The same for the file at `path`, streamed from disk (HttpClient::send_file()).
  bool put_asset_file(std::string_view sha256, const std::filesystem::path& path,
                      const HttpClient::UploadProgress& progress = {});

  // The worker's routes. A registration of another protocol version throws ApiError 409
  // (protocol_mismatch); an answer of another version throws protocol::ProtocolMismatch.
  // A registration makes this client send the secret it gave with every later request.
  protocol::Registration register_worker(const protocol::WorkerRegistration& registration);
  // Sends `secret` (a Registration's) with every request from now on: for a worker's other
  // clients. Safe while other threads use the client (a worker registers again after the
  // coordinator forgot it).
  void prove_as(std::string secret);
  // Nothing when no tile came within wait_s (204).
  std::optional<protocol::Lease> claim(std::string_view worker, double wait_s, int max_tiles);
  // Nothing when the lease is lost (410).
  std::optional<protocol::Lease> heartbeat(std::string_view lease);
  std::optional<protocol::Lease> extend(std::string_view lease, int max_tiles);
  std::string scene(std::string_view digest);  // the scene's JSON text
  // An asset a scene names, for workers: into the file `into` as it arrives, never held
  // whole (HttpClient::receive_file()).
  void scene_asset_to(std::string_view sha256, const std::filesystem::path& into);
  // Tiles' pixels (float32 RGB, one tile after another) named by `tiles`, with the rays
  // each took.
  // `render_us`: each tile's render time in microseconds, or nothing.
  protocol::ResultAnswer upload(std::string_view lease, std::span<const std::uint64_t> tiles,
                                std::span<const std::uint64_t> rays, std::string pixels,
                                std::span<const std::uint64_t> render_us = {});
  void fail(std::string_view lease, const protocol::TileFailure& failure);
  void release(std::string_view lease);
  void leave(std::string_view worker);

  // Every answer, as HttpClient::set_observer.
  void observe(HttpClient::Observer observer) { http_.set_observer(std::move(observer)); }
  void interrupt() { http_.interrupt(); }
  void clear_interrupt() { http_.clear_interrupt(); }

 private:
  // The answer, when its status is below 400 or one of `accepted`; otherwise ApiError.
  HttpResult call(std::string_view method, const std::string& target, std::string body = {},
                  std::initializer_list<int> accepted = {});
  // The worker's secret as a header, when it has one.
  HttpClient::Headers identity() const;
  HttpClient http_;
  mutable std::mutex secret_mutex_;
  std::string worker_secret_;  // "" until registered (or told by prove_as())
};

}  // namespace tessera
