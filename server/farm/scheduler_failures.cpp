// Failures: of a tile (an error reported, a lease expired), of a job (at a tile's limit,
// stalled, or unstorable), and the workers kept off a job they failed on.
#include <algorithm>
#include <set>

#include <spdlog/spdlog.h>

#include "common/scene/frame_list.hpp"

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"

namespace tessera {

void Scheduler::stage_tile_failure(StagedChange& change, JobEntry& job, int index,
                                   const WorkerEntry* worker, const std::string& error) {
  TileSlot& tile = change.tile(job, index);
  tile.attempts += 1;
  tile.last_error = error;
  // Not staged: a count kept in memory only, and harmless should the commit fail.
  if (worker) job.failures_by_worker[worker->key()] += 1;
  job.status.health.tile_failures += 1;
  job.status.health.last_problem = "tile " + std::to_string(index) + ": " + error;
  spdlog::warn("job {}: tile {} failed ({} of {} attempts): {}", job.status.id, index,
               tile.attempts, config_.max_tile_attempts, error);
  if (tile.attempts < config_.max_tile_attempts) return;
  if (job.frame_count() == 1) {
    stage_job_failure(change, job, spent_tile_error(index, job.rect(index), tile));
    return;
  }
  // An animation loses the frame, not the job: the frame's other tiles are withdrawn (its
  // pending ones leave the queue once this is applied, track_tile()), and the job goes on
  // with its other frames until every one is done or failed.
  const int slot = job.slot_of(index);
  std::set<int>& failing = change.failing_slots[&job];
  if (!job.open_slots.contains(slot) || !failing.insert(slot).second) return;
  spdlog::warn("job {}: frame {} failed: tile {} failed {} times", job.status.id,
               job.status.frames->numbers[slot], index, tile.attempts);
  std::vector<std::string> withdrawn;
  for (const auto& [lease_id, entry] : leases_)
    if (entry.job_id == job.status.id && !entry.live.empty() &&
        job.slot_of(entry.live.front()) == slot)
      withdrawn.push_back(lease_id);
  for (const std::string& lease_id : withdrawn) stage_lease_end(change, lease_id, false);
  // Settled once every open frame is failing now, or done, which a failure changes not.
  for (const int open : job.open_slots)
    if (!failing.contains(open)) return;
  std::vector<int> more;
  for (const int failed : failing) more.push_back(job.status.frames->numbers[failed]);
  stage_job_failure(change, job, failed_frames_error(job, more, change));
}

std::string Scheduler::failed_frames_error(const JobEntry& job, const std::vector<int>& more,
                                           const StagedChange& change) const {
  std::vector<int> failed = job.status.failed_frames;
  failed.insert(failed.end(), more.begin(), more.end());
  std::sort(failed.begin(), failed.end());
  failed.erase(std::unique(failed.begin(), failed.end()), failed.end());
  if (failed.empty()) return "frames failed";
  std::string error = std::to_string(failed.size()) + " of " + std::to_string(job.frame_count()) +
                      " frames failed: " + format_frame_list(failed);
  // The first failed frame's reason, as GET /v1/jobs/{id}/frames gives each.
  const std::optional<int> slot = slot_of_frame(job, failed.front());
  if (!slot) return error;
  const int first = *slot * job.tiles_per_frame;
  for (int index = first; index < first + job.tiles_per_frame; ++index) {
    const auto staged = change.tiles.find({const_cast<JobEntry*>(&job), index});
    const TileSlot& tile = staged != change.tiles.end() ? staged->second : job.tiles[index];
    if (tile.state == TileState::done || tile.attempts < config_.max_tile_attempts) continue;
    const TileRect& rect = job.rect(index);
    error += "; frame " + std::to_string(failed.front()) + ", tile " +
             std::to_string(index - first) + " at (" + std::to_string(rect.x) + ", " +
             std::to_string(rect.y) + "): " + tile.last_error;
    break;
  }
  return error;
}

void Scheduler::stage_job_failure(StagedChange& change, JobEntry& job, const std::string& error) {
  JobRecord& status = change.job(job);
  if (is_finished(status.state)) return;
  status.state = JobState::failed;
  status.finished_at_ms = clock_.now_ms();
  status.error = error;
  // Its other tiles are withdrawn from their workers, as for a cancel.
  for (const auto& [lease_id, entry] : leases_)
    if (entry.job_id == job.status.id && !entry.live.empty())
      stage_lease_end(change, lease_id, false);
}

void Scheduler::fail_stalled_locked(std::int64_t now, StagedChange& change) {
  if (config_.stall_timeout_ms <= 0) return;
  for (const auto& key : active_) {
    JobEntry& job = *jobs_.at(std::get<2>(key));
    const JobHealthRecord& health = job.status.health;
    if (job.status.state != JobState::running || job.status.tiles_rendering == 0 ||
        health.progress_at_ms <= 0 || now - health.progress_at_ms < config_.stall_timeout_ms)
      continue;
    std::string error = "no tile was delivered for " +
                        std::to_string((now - health.progress_at_ms) / 1000) +
                        " s while its tiles were being rendered";
    if (health.repeated_handouts > 0)
      error += "; tiles went out again " + std::to_string(health.repeated_handouts) + " times";
    if (!health.last_problem.empty()) error += "; the last problem: " + health.last_problem;
    stage_job_failure(change, job, error);
  }
}

void Scheduler::fail_unstorable(JobEntry& job, const std::string& error,
                                const std::vector<Delivery>& undelivered) {
  spdlog::error("job {}: {}", job.status.id, error);
  StagedChange change;
  for (const Delivery& delivery : undelivered) {
    if (delivery.job_id != job.status.id) continue;
    const TileSlot& was = job.tiles[delivery.tile];
    if (was.state != TileState::done || was.result_lease_id != delivery.lease_id) continue;
    change.job(job).rays -= was.rays;
    TileSlot& tile = change.tile(job, delivery.tile);
    tile.state = TileState::pending;
    tile.result_lease_id.clear();
    tile.rays = 0;
    tile.render_us = 0;
  }
  if (job.status.state == JobState::failed || job.status.state == JobState::canceled) {
    if (change.empty()) return;
  } else if (job.status.state == JobState::completed) {  // Its last tiles were refused after it was
                                                         // marked completed in memory.
    JobRecord& status = change.job(job);
    status.state = JobState::failed;
    status.error = error;
  } else {
    stage_job_failure(change, job, error);
  }
  StoreThread::Work work = record(change);
  apply(change);
  // Not through commit(): a refusal of this write must not fail the job again.
  const StoreTicket ticket = queue_write(std::move(work));
  store_thread_.after(
      ticket, [id = job.status.id, callbacks = finished_callbacks_](const std::string& refused) {
        if (!refused.empty())
          spdlog::error("job {}: the failure could not be stored either ({}); it is kept in memory",
                        id, refused);
        for (const auto& callback : callbacks) callback();
      });
}

bool Scheduler::kept_off(const JobEntry& job, const WorkerEntry& worker) const {
  const auto failed_too_often = [&](const WorkerEntry& w) {
    const auto it = job.failures_by_worker.find(w.key());
    return it != job.failures_by_worker.end() && it->second >= config_.worker_failures_per_job;
  };
  if (!failed_too_often(worker)) return false;
  // Only while another worker could take the tiles: with nobody else, trying again is the
  // way to the attempt limit, which ends the job instead of leaving it waiting forever.
  for (const auto& [id, other] : workers_)
    if (other.get() != &worker && is_present(other->info.state) && !failed_too_often(*other))
      return true;
  return false;
}

Written Scheduler::fail_tile(const std::string& lease_id, int tile_index,
                             const std::string& error) {
  Callbacks notify;
  Written result;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    const auto it = leases_.find(lease_id);
    if (it == leases_.end()) return pending(std::monostate{}, before);
    const std::vector<int>& live = it->second.live;
    if (std::find(live.begin(), live.end(), tile_index) == live.end())
      return pending(std::monostate{}, before);
    JobEntry& job = *jobs_.at(it->second.job_id);
    const WorkerEntry* worker = find_worker(job.tiles[tile_index].worker_id);
    StagedChange change;
    stage_lease_end(change, lease_id, false);
    stage_tile_failure(change, job, tile_index, worker, error);
    commit(change);
    notify = callbacks_;
    result = pending(std::monostate{}, before);
  }
  for (const auto& callback : notify) callback();
  return result;
}

}  // namespace tessera
