#include "server/api_json.hpp"

#include <cstdio>
#include <ctime>

#include "common/scene_parser.hpp"

namespace tessera {

std::string format_timestamp(std::int64_t ms) {
  const std::time_t seconds = static_cast<std::time_t>(ms / 1000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[80];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900,
                utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec,
                static_cast<int>(ms % 1000));
  return text;
}

std::variant<nlohmann::json, HttpResponse> json_body(const HttpRequest& request) {
  try {
    return parse_json_text(request.body);
  } catch (const SceneError& e) {
    return error_response(400, "malformed_json", e.detail());
  }
}

std::optional<std::chrono::milliseconds> wait_of(const HttpRequest& request, double fallback_s) {
  double wait_s = fallback_s;
  if (auto it = request.query.find("wait_s"); it != request.query.end()) {
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

namespace {

nlohmann::json timestamp_or_null(std::int64_t ms) {
  return ms > 0 ? nlohmann::json(format_timestamp(ms)) : nlohmann::json(nullptr);
}

nlohmann::json to_json(const JobHealth& health, const JobStatus& job, std::int64_t now_ms) {
  // How long its tiles have rendered with none delivered; 0 unless some are under lease.
  const bool rendering = job.state == JobState::running && job.tiles_rendering > 0;
  const double no_progress_s = rendering && health.progress_at_ms > 0
                                   ? std::max<std::int64_t>(0, now_ms - health.progress_at_ms) / 1e3
                                   : 0.0;
  return {{"tile_failures", health.tile_failures},
          {"refused_results", health.refused_results},
          {"repeated_handouts", health.repeated_handouts},
          {"last_problem", health.last_problem.empty() ? nlohmann::json(nullptr)
                                                       : nlohmann::json(health.last_problem)},
          {"no_progress_s", no_progress_s}};
}

}  // namespace

nlohmann::json to_json(const JobStatus& job, std::int64_t now_ms) {
  const double progress =
      job.tiles_total > 0 ? static_cast<double>(job.tiles_done) / job.tiles_total : 0.0;
  double elapsed_s = 0.0;
  if (job.started_at_ms > 0)
    elapsed_s = ((job.finished_at_ms > 0 ? job.finished_at_ms : now_ms) - job.started_at_ms) / 1e3;
  // The remaining tiles at the rate seen so far; unknown before the first tile is done.
  nlohmann::json eta = nullptr;
  if (job.state == JobState::completed) {
    eta = 0.0;
  } else if (!is_finished(job.state) && job.tiles_done > 0 && elapsed_s > 0) {
    eta = elapsed_s * (job.tiles_total - job.tiles_done) / job.tiles_done;
  }
  return {
      {"id", job.id},
      {"name", job.name},
      {"state", to_string(job.state)},
      {"priority", job.priority},
      {"width", job.width},
      {"height", job.height},
      {"tiles",
       {{"total", job.tiles_total}, {"done", job.tiles_done}, {"rendering", job.tiles_rendering}}},
      {"progress", progress},
      {"created_at", format_timestamp(job.created_at_ms)},
      {"started_at", timestamp_or_null(job.started_at_ms)},
      {"finished_at", timestamp_or_null(job.finished_at_ms)},
      {"elapsed_s", elapsed_s},
      {"eta_s", eta},
      {"error", job.error.empty() ? nlohmann::json(nullptr) : nlohmann::json(job.error)},
      {"health", to_json(job.health, job, now_ms)},
      {"stats", {{"rays", job.rays}, {"rays_per_s", elapsed_s > 0 ? job.rays / elapsed_s : 0.0}}}};
}

nlohmann::json to_json(const WorkerInfo& worker) {
  return {{"id", worker.id},
          {"name", worker.name},
          {"host", worker.host},
          {"threads", worker.threads},
          {"state", worker.state},
          {"current_job", worker.current_job.empty() ? nlohmann::json(nullptr)
                                                     : nlohmann::json(worker.current_job)},
          {"current_tile",
           worker.current_tile >= 0 ? nlohmann::json(worker.current_tile) : nlohmann::json(nullptr)},
          {"tiles_rendered", worker.tiles_rendered},
          {"last_seen", format_timestamp(worker.last_seen_ms)}};
}

nlohmann::json to_json(const Lease& lease, std::int64_t now_ms) {
  nlohmann::json tiles = nlohmann::json::array();
  for (const LeaseTile& tile : lease.tiles)
    tiles.push_back({{"index", tile.index},
                     {"x", tile.rect.x},
                     {"y", tile.rect.y},
                     {"width", tile.rect.width},
                     {"height", tile.rect.height}});
  return {{"id", lease.id},
          {"job_id", lease.job_id},
          {"scene_digest", lease.scene_digest},
          {"tiles", std::move(tiles)},
          {"expires_in_s", std::max<std::int64_t>(0, lease.expires_at_ms - now_ms) / 1e3}};
}

}  // namespace tessera
