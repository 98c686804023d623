// Leases: how a batch of tiles is bound to a worker, kept alive, delivered, given back or
// lost.
//
// A tile is "live" under a lease from the grant until its result is accepted, the worker
// gives the lease back or leaves, the job is canceled, or the lease is reaped after
// expiring. Reaping happens in expire_leases(), in claim() (so that no worker waits for
// the periodic sweep) and in a heartbeat that arrives too late. A result for an expired
// lease that has not been reaped yet is accepted: nobody else has the tiles, so the work
// is valid. Once reaped, the tiles may go to another worker under a new lease id, and the
// old id is refused as stale: a tile's pixels always come from exactly one lease, the one
// recorded as its result_lease_id.
#include <algorithm>
#include <set>

#include <spdlog/spdlog.h>
#include "server/farm/ids.hpp"

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"

namespace tessera {
namespace {

// Why a job fails of tiles handed out too often; names the first of them.
std::string handouts_error(const JobEntry& job, const std::vector<int>& tiles, int limit) {
  const int index = *std::min_element(tiles.begin(), tiles.end(),
                                      [&](int a, int b) { return job.rank[a] < job.rank[b]; });
  const TileRect& rect = job.rect(index);
  std::string error = "tile " + std::to_string(index) + " at (" + std::to_string(rect.x) + ", " +
                      std::to_string(rect.y) + ") went out to workers " + std::to_string(limit) +
                      " times without its result being accepted";
  if (!job.status.health.last_problem.empty())
    error += "; the last problem: " + job.status.health.last_problem;
  return error;
}

}  // namespace

int Scheduler::batch_size(const JobEntry& job, int max_tiles) const {
  const int pending = static_cast<int>(job.pending.size());
  if (max_tiles <= 1 || pending <= 1) return 1;
  // At most half of an even share of what is left, so that batches shrink as the job nears
  // its end and its last tiles spread over every worker instead of queueing behind one.
  const int share = pending / (2 * std::max(1, present_workers_));
  return std::clamp(share, 1, std::min(max_tiles, pending));
}

Pending<std::optional<LeaseRecord>> Scheduler::claim(const std::string& worker_id, int max_tiles) {
  Callbacks notify;
  Pending<std::optional<LeaseRecord>> answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    std::optional<LeaseRecord> result;
    WorkerEntry* worker = find_worker(worker_id);
    // One that left registers again first.
    if (!worker || worker->info.state == WorkerState::left) return pending(result, before);
    const std::int64_t now = clock_.now_ms();
    if (expire_locked(now)) notify = callbacks_;

    if (!worker->lease_id.empty()) {
      // A reconnecting worker (or a retried request) gets its own live lease back, so
      // one worker never holds two leases. It renders those tiles again: that counts as
      // a hand-out, so that a worker that keeps dropping its lease and claiming it back
      // (its results refused, say) ends at the limit instead of looping.
      note_seen(*worker, now);
      // The count is kept in memory only, so nothing is written unless it ends the job.
      const std::string lease_id = worker->lease_id;
      const LeaseTiles& entry = leases_.at(lease_id);
      JobEntry& job = *jobs_.at(entry.job_id);
      bool over = false;
      for (const int index : entry.live) {
        count_handout(job, job.tiles[index]);
        over = over || job.tiles[index].handouts > config_.max_tile_handouts;
      }
      if (over) {
        StagedChange change;
        stage_job_failure(change, job, handouts_error(job, entry.live, config_.max_tile_handouts));
        commit(change);
        notify = callbacks_;
      } else {
        result = lease_of(lease_id);
      }
    } else {
      // A draining worker is given nothing new.
      JobEntry* chosen = worker->info.draining ? nullptr : next_job_for(*worker);
      if (!chosen && worker->info.state == WorkerState::idle) {
        note_seen(*worker, now);
      } else {
        StagedChange change;
        WorkerEntry& staged_worker = change.worker(*worker);
        staged_worker.info.last_seen_ms = now;
        staged_worker.info.state = WorkerState::idle;  // asking for work also revives a gone worker
        if (chosen) {
          const std::string lease_id = new_lease_id();
          const std::vector<int> batch =
              stage_batch(change, *chosen, lease_id, worker_id, batch_size(*chosen, max_tiles),
                          now + config_.lease_timeout_ms, false);
          staged_worker.info.current_tile = batch.front();
          // Rendering (re)starts: the stall clock counts from here, not from the last
          // delivery before a pause (no workers, a job of higher priority in between).
          if (chosen->status.tiles_rendering == 0) chosen->status.health.progress_at_ms = now;
          if (chosen->status.state == JobState::queued) {
            JobRecord& status = change.job(*chosen);
            status.state = JobState::running;
            if (status.started_at_ms == 0) status.started_at_ms = now;
          }
          staged_worker.lease_id = lease_id;
          staged_worker.info.state = WorkerState::rendering;
          staged_worker.info.current_job = chosen->status.id;
        }
        commit(change);
        if (chosen) result = lease_of(worker->lease_id);
      }
    }
    answer = pending(std::move(result), before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

JobEntry* Scheduler::next_job_for(const WorkerEntry& worker) const {
  for (const auto& key : active_) {
    JobEntry& job = *jobs_.at(std::get<2>(key));
    if (!job.pending.empty() && !kept_off(job, worker)) return &job;
  }
  return nullptr;
}

std::vector<int> Scheduler::stage_batch(StagedChange& change, JobEntry& job,
                                        const std::string& lease_id, const std::string& worker_id,
                                        int count, std::int64_t expires_ms, bool extending,
                                        int slot) {
  std::vector<int> batch;
  // Shared by the batch's tiles, rather than a copy of each id in each.
  const SharedText lease(lease_id);
  const SharedText worker = worker_text(worker_id);
  int position = job.pending.first_from(0);  // staging leaves the pending set alone
  for (int i = 0; i < count && position >= 0;
       ++i, position = job.pending.first_from(position + 1)) {
    const int index = job.order[position];
    // Frames go out in order, so the first pending tile not of the lease's frame ends it.
    if (slot < 0) slot = job.slot_of(index);
    if (job.slot_of(index) != slot) break;
    // A tile that failed before goes out alone, as the first of a new lease, so that
    // another failure is charged to it and not to tiles that happened to share its batch.
    if ((i > 0 || extending) && job.tiles[index].attempts > 0) break;
    TileSlot& tile = change.tile(job, index);
    tile.state = TileState::leased;
    tile.lease_id = lease;
    tile.worker_id = worker;
    tile.lease_expires_ms = expires_ms;
    count_handout(job, tile);
    batch.push_back(index);
    if (tile.attempts > 0) break;
  }
  return batch;
}

Pending<std::optional<LeaseRecord>> Scheduler::extend(const std::string& lease_id, int max_tiles) {
  Callbacks notify;
  Pending<std::optional<LeaseRecord>> answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    std::optional<LeaseRecord> result;
    const std::int64_t now = clock_.now_ms();
    if (expire_locked(now)) notify = callbacks_;
    const auto it = leases_.find(lease_id);
    if (it != leases_.end() && !it->second.live.empty()) {
      const std::vector<int> live = it->second.live;  // commit() rewrites the index
      JobEntry& job = *jobs_.at(it->second.job_id);
      const std::string worker_id = job.tiles[live.front()].worker_id;
      WorkerEntry* worker = find_worker(worker_id);
      StagedChange change;
      // Every live tile shares one expiry: the old ones are renewed with the new.
      const std::int64_t expires = now + config_.lease_timeout_ms;
      renew_lease(lease_id, expires);
      std::vector<int> added;
      // Only while the lease's job is the one a claim would choose for this worker: a
      // job of higher priority gets the worker at the end of this lease, as it would
      // after any batch.
      const int room = config_.max_lease_tiles - static_cast<int>(live.size());
      if (worker && !worker->info.draining && room > 0 && next_job_for(*worker) == &job)
        added = stage_batch(change, job, lease_id, worker_id,
                            std::min(batch_size(job, max_tiles), room), expires, true,
                            job.slot_of(live.front()));
      commit(change);
      if (worker) note_seen(*worker, now);
      LeaseRecord lease = lease_of(lease_id);
      lease.tiles.clear();
      // In hand-out order, as stage_batch() took them.
      for (const int index : added) lease.tiles.push_back({index, job.rect(index)});
      result = std::move(lease);
    }
    answer = pending(std::move(result), before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

Pending<std::optional<LeaseRecord>> Scheduler::heartbeat(const std::string& lease_id) {
  Callbacks notify;
  Pending<std::optional<LeaseRecord>> answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    std::optional<LeaseRecord> result;
    const auto it = leases_.find(lease_id);
    if (it == leases_.end() || it->second.live.empty()) return pending(result, before);
    const std::vector<int> live = it->second.live;  // commit() rewrites the index
    JobEntry& job = *jobs_.at(it->second.job_id);
    const TileSlot& first = job.tiles[live.front()];
    const std::int64_t now = clock_.now_ms();
    StagedChange change;
    if (now >= first.lease_expires_ms) {
      // Too late: the worker is told it lost the tiles, so they can go out again now.
      stage_lease_end(change, lease_id, true);
      commit(change);
      notify = callbacks_;
    } else {
      renew_lease(lease_id, now + config_.lease_timeout_ms);
      if (WorkerEntry* worker = find_worker(first.worker_id)) note_seen(*worker, now);
      result = lease_of(lease_id);
    }
    answer = pending(std::move(result), before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

Written Scheduler::release(const std::string& lease_id) {
  Callbacks notify;
  Written answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    const auto it = leases_.find(lease_id);
    if (it == leases_.end() || it->second.live.empty()) return pending(std::monostate{}, before);
    StagedChange change;
    stage_lease_end(change, lease_id, false);
    commit(change);
    notify = callbacks_;
    answer = pending(std::monostate{}, before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

Written Scheduler::expire_leases() {
  Callbacks notify;
  Written answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    const std::int64_t now = clock_.now_ms();
    if (expire_locked(now)) notify = callbacks_;
    forget_workers_locked(now);
    StagedChange change;
    fail_stalled_locked(now, change);
    if (!change.empty()) {
      commit(change);
      notify = callbacks_;
    }
    answer = pending(std::monostate{}, before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

bool Scheduler::expire_locked(std::int64_t now) {
  std::vector<std::string> expired;
  for (auto it = expiries_.begin(); it != expiries_.end() && it->first <= now; ++it)
    expired.push_back(it->second);
  if (expired.empty()) return false;
  StagedChange change;
  for (const std::string& lease_id : expired) {
    spdlog::warn("lease {} expired without a heartbeat; its tiles go back to the queue", lease_id);
    stage_lease_end(change, lease_id, true);
  }
  commit(change);
  return true;
}

void Scheduler::stage_lease_end(StagedChange& change, const std::string& lease_id, bool expired) {
  const auto it = leases_.find(lease_id);
  if (it == leases_.end() || it->second.live.empty()) return;
  JobEntry& job = *jobs_.at(it->second.job_id);
  std::vector<int> owed = it->second.live;
  std::sort(owed.begin(), owed.end(), [&](int a, int b) { return job.rank[a] < job.rank[b]; });
  const std::string worker_id = job.tiles[owed.front()].worker_id;
  WorkerEntry* worker = find_worker(worker_id);
  std::vector<int> ended;
  for (const int index : owed) {
    TileSlot& tile = change.tile(job, index);
    if (tile.lease_id != lease_id) continue;  // already staged by an earlier call
    tile.state = TileState::pending;
    tile.lease_id.clear();
    tile.worker_id.clear();
    tile.lease_expires_ms = 0;
    ended.push_back(index);
  }
  // A tile back in the queue after its last allowed hand-out: going out again would only
  // repeat whatever kept its result from being accepted.
  std::vector<int> worn;
  for (const int index : ended)
    if (change.tile(job, index).handouts >= config_.max_tile_handouts) worn.push_back(index);
  if (!worn.empty())
    stage_job_failure(change, job, handouts_error(job, worn, config_.max_tile_handouts));
  if (worker) {
    WorkerEntry& staged = change.worker(*worker);
    if (staged.lease_id == lease_id) {
      staged.lease_id.clear();
      staged.info.current_job.clear();
      staged.info.current_tile = -1;
      if (staged.info.state == WorkerState::rendering) staged.info.state = WorkerState::idle;
    }
  }
  if (!expired) return;
  counters_.lease_expiries += 1;
  // Any of the tiles still owed may be the one the worker crashed or hung on. Each is
  // charged, and goes out alone next time (see claim()), where a further failure is its own.
  const std::string who =
      worker ? "worker " + worker->info.name + " on " + worker->info.host : "its worker";
  for (const int index : ended)
    stage_tile_failure(change, job, index, worker, who + " stopped responding (its lease expired)");
}

void Scheduler::count_handout(JobEntry& job, TileSlot& tile) {
  tile.handouts += 1;
  if (tile.handouts > 1) {
    job.status.health.repeated_handouts += 1;
    counters_.tile_retries += 1;
  }
}

LeaseRecord Scheduler::lease_of(const std::string& lease_id) const {
  const LeaseTiles& entry = leases_.at(lease_id);
  const JobEntry& job = *jobs_.at(entry.job_id);
  std::vector<int> live = entry.live;
  std::sort(live.begin(), live.end(), [&](int a, int b) { return job.rank[a] < job.rank[b]; });
  LeaseRecord lease;
  lease.id = lease_id;
  lease.job_id = job.status.id;
  lease.scene_digest = job.status.scene_digest;
  if (!live.empty()) {
    lease.frame = job.frame_of_tile(live.front());
    lease.worker_id = job.tiles[live.front()].worker_id;
    lease.expires_at_ms = job.tiles[live.front()].lease_expires_ms;
  }
  for (const int index : live) lease.tiles.push_back({index, job.rect(index)});
  return lease;
}

std::string Scheduler::new_lease_id() const {
  std::string id;
  do {
    id = "l-" + random_hex(16);
  } while (leases_.contains(id));
  return id;
}

}  // namespace tessera
