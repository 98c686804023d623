// Leases: how a tile is bound to a worker, kept alive, delivered, given back or lost.
//
// A lease is "current" while it is its tile's lease: from the grant until the result is
// accepted, the worker gives it back or leaves, the job is canceled, or the lease is
// reaped after expiring. Reaping happens in expire_leases(), in claim() (so that no
// worker waits for the periodic sweep) and in a heartbeat that arrives too late.
// A result for an expired lease that has not been reaped yet is accepted: nobody else
// has the tile, so the work is valid. Once reaped, the tile may go to another worker under
// a new lease id, and the old id is refused as stale: a tile's pixels always come from
// exactly one lease, the one recorded as its result_lease_id.
#include <algorithm>

#include "server/ids.hpp"
#include <spdlog/spdlog.h>

#include "server/scheduler.hpp"
#include "server/scheduler_entries.hpp"

namespace tessera {

std::optional<Lease> Scheduler::claim(const std::string& worker_id) {
  Callbacks notify;
  std::optional<Lease> result;
  {
    std::lock_guard lock(mutex_);
    WorkerEntry* worker = find_worker(worker_id);
    if (!worker) return std::nullopt;
    const std::int64_t now = clock_.now_ms();
    if (expire_locked(now)) notify = callbacks_;

    if (!worker->lease_id.empty()) {
      // A reconnecting worker (or a retried request) gets its own live lease back, so
      // one worker never holds two tiles.
      note_seen(*worker, now);
      const TileRef& ref = leases_.at(worker->lease_id);
      result = lease_of(*jobs_.at(ref.job_id), ref.tile_index);
    } else {
      JobEntry* chosen = nullptr;
      for (const auto& key : active_) {
        JobEntry& job = *jobs_.at(std::get<2>(key));
        if (!job.pending.empty()) {
          chosen = &job;
          break;
        }
      }
      if (!chosen && worker->info.state == worker_idle) {
        note_seen(*worker, now);
      } else {
        StagedChange change;
        WorkerEntry& staged_worker = change.worker(*worker);
        staged_worker.info.last_seen_ms = now;
        staged_worker.info.state = worker_idle;  // asking for work also revives a gone worker
        int index = -1;
        if (chosen) {
          index = chosen->order[*chosen->pending.begin()];
          TileSlot& tile = change.tile(*chosen, index);
          tile.state = TileState::leased;
          tile.lease_id = new_lease_id();
          tile.worker_id = worker_id;
          tile.lease_expires_ms = now + config_.lease_timeout_ms;
          if (chosen->status.state == JobState::queued) {
            JobStatus& status = change.job(*chosen);
            status.state = JobState::running;
            if (status.started_at_ms == 0) status.started_at_ms = now;
          }
          staged_worker.lease_id = tile.lease_id;
          staged_worker.info.state = worker_rendering;
          staged_worker.info.current_job = chosen->status.id;
          staged_worker.info.current_tile = index;
        }
        commit(change);
        if (chosen) result = lease_of(*chosen, index);
      }
    }
  }
  for (const auto& callback : notify) callback();
  return result;
}

std::optional<Lease> Scheduler::heartbeat(const std::string& lease_id) {
  Callbacks notify;
  std::optional<Lease> result;
  {
    std::lock_guard lock(mutex_);
    const auto it = leases_.find(lease_id);
    if (it == leases_.end()) return std::nullopt;
    JobEntry& job = *jobs_.at(it->second.job_id);
    const int index = it->second.tile_index;
    const std::int64_t now = clock_.now_ms();
    StagedChange change;
    if (now >= job.tiles[index].lease_expires_ms) {
      // Too late: the worker is told it lost the tile, so the tile can go out again now.
      stage_lease_end(change, lease_id, true);
      commit(change);
      notify = callbacks_;
    } else {
      change.tile(job, index).lease_expires_ms = now + config_.lease_timeout_ms;
      commit(change);
      if (WorkerEntry* worker = find_worker(job.tiles[index].worker_id)) note_seen(*worker, now);
      result = lease_of(job, index);
    }
  }
  for (const auto& callback : notify) callback();
  return result;
}

ResultOutcome Scheduler::complete(const std::string& lease_id, std::span<const float> pixels,
                                  std::uint64_t rays) {
  std::lock_guard lock(mutex_);
  const auto it = leases_.find(lease_id);
  if (it == leases_.end())
    return delivered_.contains(lease_id) ? ResultOutcome::duplicate : ResultOutcome::stale;
  JobEntry& job = *jobs_.at(it->second.job_id);
  const int index = it->second.tile_index;
  const TileSlot& current = job.tiles[index];
  if (pixels.size() != current.rect.pixel_count() * 3) return ResultOutcome::wrong_size;

  const std::int64_t now = clock_.now_ms();
  StagedChange change;
  TileSlot& tile = change.tile(job, index);
  tile.state = TileState::done;
  tile.lease_id.clear();
  tile.lease_expires_ms = 0;
  tile.rays = rays;
  tile.result_lease_id = lease_id;  // worker_id stays: who rendered it
  change.pixels = StagedChange::Pixels{&job, index, pixels};

  JobStatus& status = change.job(job);
  status.rays += rays;
  const bool job_done = job.status.tiles_done + 1 == job.status.tiles_total;
  if (job_done) {
    status.state = JobState::completed;
    status.finished_at_ms = now;
  }
  if (WorkerEntry* worker = find_worker(current.worker_id)) {
    WorkerEntry& staged = change.worker(*worker);
    staged.info.tiles_rendered += 1;
    staged.info.last_seen_ms = now;
    if (staged.lease_id == lease_id) {
      staged.lease_id.clear();
      staged.info.current_job.clear();
      staged.info.current_tile = -1;
      staged.info.state = worker_idle;
    }
  }
  commit(change);
  // After the commit: should the write fail or the process die, the tiles are stored and
  // a restart writes the image again.
  if (job_done) finish_image(job);
  return ResultOutcome::accepted;
}

void Scheduler::release(const std::string& lease_id) {
  Callbacks notify;
  {
    std::lock_guard lock(mutex_);
    if (!leases_.contains(lease_id)) return;
    StagedChange change;
    stage_lease_end(change, lease_id, false);
    commit(change);
    notify = callbacks_;
  }
  for (const auto& callback : notify) callback();
}

void Scheduler::expire_leases() {
  Callbacks notify;
  {
    std::lock_guard lock(mutex_);
    if (expire_locked(clock_.now_ms())) notify = callbacks_;
  }
  for (const auto& callback : notify) callback();
}

bool Scheduler::expire_locked(std::int64_t now) {
  std::vector<std::string> expired;
  for (const auto& [lease_id, ref] : leases_)
    if (now >= jobs_.at(ref.job_id)->tiles[ref.tile_index].lease_expires_ms)
      expired.push_back(lease_id);
  if (expired.empty()) return false;
  StagedChange change;
  for (const std::string& lease_id : expired) {
    spdlog::warn("lease {} expired without a heartbeat; its tile goes back to the queue", lease_id);
    stage_lease_end(change, lease_id, true);
  }
  commit(change);
  return true;
}

void Scheduler::stage_lease_end(StagedChange& change, const std::string& lease_id, bool expired) {
  const auto it = leases_.find(lease_id);
  if (it == leases_.end()) return;
  JobEntry& job = *jobs_.at(it->second.job_id);
  TileSlot& tile = change.tile(job, it->second.tile_index);
  const std::string worker_id = tile.worker_id;
  tile.state = TileState::pending;
  tile.lease_id.clear();
  tile.worker_id.clear();
  tile.lease_expires_ms = 0;
  if (expired) tile.attempts += 1;
  if (WorkerEntry* worker = find_worker(worker_id)) {
    WorkerEntry& staged = change.worker(*worker);
    if (staged.lease_id == lease_id) {
      staged.lease_id.clear();
      staged.info.current_job.clear();
      staged.info.current_tile = -1;
      if (staged.info.state == worker_rendering) staged.info.state = worker_idle;
    }
  }
}

Lease Scheduler::lease_of(const JobEntry& job, int index) const {
  const TileSlot& tile = job.tiles[index];
  Lease lease;
  lease.id = tile.lease_id;
  lease.job_id = job.status.id;
  lease.worker_id = tile.worker_id;
  lease.tile_index = index;
  lease.rect = tile.rect;
  lease.scene_digest = job.status.scene_digest;
  lease.expires_at_ms = tile.lease_expires_ms;
  return lease;
}

std::string Scheduler::new_lease_id() const {
  std::string id;
  do {
    id = "l-" + random_hex(16);
  } while (leases_.contains(id) || delivered_.contains(id));
  return id;
}

}  // namespace tessera
