#include "server/api/api_json.hpp"

#include <algorithm>

#include "common/protocol/paths.hpp"
#include "common/protocol/timestamp.hpp"
#include "common/scene/frame_list.hpp"
#include "common/scene/scene_parser.hpp"

namespace tessera {

using protocol::format_timestamp;

std::variant<nlohmann::json, HttpResponse> json_body(const HttpRequest& request) {
  try {
    return parse_json_text(request.body);
  } catch (const SceneError& e) {
    return error_response(400, "malformed_json", e.detail());
  }
}

HttpResponse invalid_request(const protocol::ProtocolError& error) {
  return error_response(400, "invalid_request", error.message(), error.pointer());
}

std::variant<std::size_t, HttpResponse> query_count(const HttpRequest& request,
                                                    std::string_view name, std::size_t min,
                                                    std::size_t max, std::size_t fallback) {
  const auto it = request.query.find(std::string(name));
  if (it == request.query.end()) return fallback;
  const std::string& text = it->second;
  std::size_t value = 0;
  bool valid = !text.empty() && text.size() <= 12;
  for (const char c : text) {
    valid = valid && c >= '0' && c <= '9';
    if (valid) value = value * 10 + static_cast<std::size_t>(c - '0');
  }
  if (valid && value >= min && value <= max) return value;
  return error_response(400, "invalid_request",
                        std::string(name) + " must be an integer from " + std::to_string(min) +
                            " to " + std::to_string(max));
}

std::optional<std::chrono::milliseconds> wait_of(const HttpRequest& request, double fallback_s) {
  double wait_s = fallback_s;
  if (auto it = request.query.find(std::string(protocol::query::wait_s));
      it != request.query.end()) {
    try {
      std::size_t used = 0;
      wait_s = std::stod(it->second, &used);
      if (used != it->second.size()) return std::nullopt;
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  if (!(wait_s >= 0 && wait_s <= 60)) return std::nullopt;
  return std::chrono::milliseconds(static_cast<long>(wait_s * 1000));
}

HttpResponse bad_wait() {
  return error_response(400, "invalid_request", "wait_s must be a number from 0 to 60");
}

namespace {

std::optional<std::string> timestamp_unless_zero(std::int64_t ms) {
  if (ms <= 0) return std::nullopt;
  return format_timestamp(ms);
}

std::optional<std::string> unless_empty(const std::string& text) {
  if (text.empty()) return std::nullopt;
  return text;
}

protocol::JobHealth health_of(const JobHealthRecord& health, const JobRecord& job,
                              std::int64_t now_ms) {
  // How long its tiles have rendered with none delivered; 0 unless some are under lease.
  const bool rendering = job.state == JobState::running && job.tiles_rendering > 0;
  const double no_progress_s = rendering && health.progress_at_ms > 0
                                   ? std::max<std::int64_t>(0, now_ms - health.progress_at_ms) / 1e3
                                   : 0.0;
  return {health.tile_failures, health.refused_results, health.repeated_handouts,
          unless_empty(health.last_problem), no_progress_s};
}

}  // namespace

protocol::JobStatus status_of(const JobRecord& job, std::int64_t now_ms) {
  protocol::JobStatus status;
  status.id = job.id;
  status.name = job.name;
  status.state = job.state;
  status.priority = job.priority;
  status.width = job.width;
  status.height = job.height;
  status.tiles = {job.tiles_total, job.tiles_done, job.tiles_rendering};
  status.progress =
      job.tiles_total > 0 ? static_cast<double>(job.tiles_done) / job.tiles_total : 0.0;
  if (job.started_at_ms > 0)
    status.elapsed_s =
        ((job.finished_at_ms > 0 ? job.finished_at_ms : now_ms) - job.started_at_ms) / 1e3;
  // The remaining tiles at the rate seen so far; unknown before the first tile is done.
  if (job.state == JobState::completed)
    status.eta_s = 0.0;
  else if (!is_finished(job.state) && job.tiles_done > 0 && status.elapsed_s > 0)
    status.eta_s = status.elapsed_s * (job.tiles_total - job.tiles_done) / job.tiles_done;
  status.created_at = format_timestamp(job.created_at_ms);
  status.started_at = timestamp_unless_zero(job.started_at_ms);
  status.finished_at = timestamp_unless_zero(job.finished_at_ms);
  status.error = unless_empty(job.error);
  status.health = health_of(job.health, job, now_ms);
  status.stats = {job.rays, status.elapsed_s > 0 ? job.rays / status.elapsed_s : 0.0};
  status.frames.list = job.frames->animated() ? job.frames->list : "0";
  status.frames.total = static_cast<int>(job.frames->numbers.size());
  status.frames.done = job.frames_done;
  status.frames.failed = static_cast<int>(job.failed_frames.size());
  status.frames.failed_list = format_frame_list(job.failed_frames);
  status.frames.current = job.current_frame;
  return status;
}

protocol::FrameStatus frame_status_of(const FrameRecord& frame) {
  protocol::FrameStatus status;
  status.frame = frame.frame;
  status.state = frame.state;
  status.tiles = {frame.tiles_total, frame.tiles_done, frame.tiles_rendering};
  status.error = unless_empty(frame.error);
  return status;
}

protocol::Worker worker_of(const WorkerRecord& worker) {
  protocol::Worker w;
  w.id = worker.id;
  w.name = worker.name;
  w.host = worker.host;
  w.threads = worker.threads;
  w.state = worker.state;
  w.current_job = unless_empty(worker.current_job);
  if (worker.current_tile >= 0) w.current_tile = worker.current_tile;
  w.tiles_rendered = worker.tiles_rendered;
  w.last_seen = format_timestamp(worker.last_seen_ms);
  w.draining = worker.draining;
  w.tiles_per_min = worker.tiles_per_min;
  w.rays_per_s = worker.rays_per_s;
  return w;
}

protocol::Lease lease_of(const LeaseRecord& lease, std::int64_t now_ms) {
  protocol::Lease l;
  l.id = lease.id;
  l.job_id = lease.job_id;
  l.scene_digest = lease.scene_digest;
  l.frame = lease.frame;
  l.tiles.reserve(lease.tiles.size());
  for (const LeaseTileRecord& tile : lease.tiles)
    l.tiles.push_back({tile.index, tile.rect.x, tile.rect.y, tile.rect.width, tile.rect.height});
  l.expires_in_s = std::max<std::int64_t>(0, lease.expires_at_ms - now_ms) / 1e3;
  return l;
}

void respond_durable(Scheduler& scheduler, Respond respond, std::function<HttpResponse()> make) {
  // Counted before the answer is made: a refusal counted later is not in it.
  const std::uint64_t refusals = scheduler.refusals();
  HttpResponse now = make();
  respond_when_stored(scheduler, scheduler.durable(), std::move(respond),
                      [&scheduler, refusals, now = std::move(now), make = std::move(make)](
                          std::monostate, const std::string&) {
                        return scheduler.refusals() == refusals ? now : make();
                      });
}

HttpResponse storage_failed(const std::string& what, const std::string& error) {
  return error_response(507, "storage_failed", "cannot store " + what + ": " + error);
}

}  // namespace tessera
