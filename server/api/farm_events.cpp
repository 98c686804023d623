#include "server/api/farm_events.hpp"

#include <nlohmann/json.hpp>

#include "common/image/image_io.hpp"
#include "common/protocol/events.hpp"
#include "common/protocol/jobs.hpp"
#include "common/protocol/workers.hpp"
#include "server/api/api_json.hpp"

namespace tessera {
namespace {

using nlohmann::json;

constexpr char kBase64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

std::string base64(const std::vector<std::uint8_t>& bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    out += kBase64[v >> 18];
    out += kBase64[(v >> 12) & 63];
    out += kBase64[(v >> 6) & 63];
    out += kBase64[v & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const std::uint32_t v = (bytes[i] << 16) | (two ? bytes[i + 1] << 8 : 0);
    out += kBase64[v >> 18];
    out += kBase64[(v >> 12) & 63];
    out += two ? kBase64[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string dumped(const json& value) {
  return value.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace

protocol::TileStatus tile_status(const FarmObserver::TileChange& tile) {
  protocol::TileStatus status;
  status.index = tile.index;
  status.frame = tile.frame;
  status.x = tile.rect.x;
  status.y = tile.rect.y;
  status.width = tile.rect.width;
  status.height = tile.rect.height;
  status.state = tile.view;
  if (!tile.worker_id.empty()) {
    status.worker = tile.worker_id;
    status.worker_name = tile.worker_name;
  }
  if (tile.view == protocol::TileView::done && tile.render_us > 0)
    status.render_ms = static_cast<double>(tile.render_us) / 1000.0;
  return status;
}

std::string tile_event_data(const FarmObserver::TileChange& tile) {
  protocol::TileStatus status = tile_status(tile);
  if (tile.view == protocol::TileView::done && !tile.pixels.empty()) {
    // 8-bit codes as the job's PNG holds them: a quarter of the floats, and what a
    // browser's canvas takes as it is.
    std::vector<std::uint8_t> codes(tile.pixels.size());
    for (std::size_t i = 0; i < codes.size(); ++i) codes[i] = code8(tile.pixels[i], tile.transfer);
    status.pixels = base64(codes);
  }
  return dumped(protocol::to_json(status));
}

void FarmEvents::send_job(const JobRecord& job) {
  hub_.publish(std::string(protocol::event::job),
               dumped(protocol::to_json(status_of(job, clock_.now_ms()))), true, job.id);
}

void FarmEvents::send_worker(const WorkerRecord& worker, WorkerChange change) {
  hub_.publish(std::string(protocol::event::worker),
               dumped(protocol::to_json(protocol::WorkerEvent{change, worker_of(worker)})), true);
}

void FarmEvents::jobs_changed(const std::vector<JobRecord>& jobs) {
  for (const JobRecord& job : jobs) {
    bool now = false;
    {
      std::lock_guard lock(mutex_);
      const auto told = told_.find(job.id);
      now = told == told_.end() || told->second != std::pair{job.state, job.priority};
      if (now) {
        dirty_jobs_.erase(job.id);
        if (is_finished(job.state))
          told_.erase(job.id);
        else
          told_[job.id] = {job.state, job.priority};
      } else {
        dirty_jobs_[job.id] = job;
      }
    }
    if (now) send_job(job);
  }
}

void FarmEvents::tiles_changed(const std::vector<TileChange>& tiles) {
  for (const TileChange& tile : tiles)
    hub_.publish(std::string(protocol::event::tile), tile_event_data(tile), false, tile.job_id);
}

void FarmEvents::workers_changed(
    const std::vector<std::pair<WorkerRecord, WorkerChange>>& workers) {
  for (const auto& [worker, change] : workers) {
    if (change == WorkerChange::changed) {
      std::lock_guard lock(mutex_);
      dirty_workers_[worker.id] = worker;
      continue;
    }
    {
      std::lock_guard lock(mutex_);
      dirty_workers_.erase(worker.id);
    }
    send_worker(worker, change);
  }
}

bool FarmEvents::wants_tiles(const std::string& job_id) {
  // Nobody follows the job: its tile events are not made, and a stream that resumes from
  // before now is told to resync instead of missing them.
  return hub_.follows_or_skips(job_id);
}

void FarmEvents::job_removed(const std::string& job_id) {
  {
    std::lock_guard lock(mutex_);
    dirty_jobs_.erase(job_id);
    told_.erase(job_id);
  }
  hub_.publish(std::string(protocol::event::job_removed),
               dumped(protocol::to_json(protocol::JobRemoved{job_id})), true, job_id);
}

void FarmEvents::flush() {
  std::map<std::string, JobRecord> jobs;
  std::map<std::string, WorkerRecord> workers;
  {
    std::lock_guard lock(mutex_);
    jobs.swap(dirty_jobs_);
    workers.swap(dirty_workers_);
  }
  for (const auto& [id, job] : jobs) send_job(job);
  if (workers.empty()) return;
  if (scheduler_)
    for (const WorkerRecord& now : scheduler_->workers())
      if (const auto it = workers.find(now.id); it != workers.end()) it->second = now;
  for (const auto& [id, worker] : workers) send_worker(worker, WorkerChange::changed);
}

}  // namespace tessera
