// The Scheduler's bookkeeping: how staged changes reach the store and then memory, and
// the indexes (pending tiles, live leases, delivered leases, claimable jobs) that follow
// every tile and job change.
#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"
#include "server/farm/tile_order.hpp"

namespace tessera {

StoreTicket Scheduler::commit(StagedChange& change, const std::string& what) {
  StoreThread::Work work = record(change);
  std::set<std::string> touched;
  for (const auto& [job, status] : change.jobs) touched.insert(job->status.id);
  for (const auto& [key, tile] : change.tiles) touched.insert(key.first->status.id);
  bool finishes = false;
  for (const auto& [job, status] : change.jobs)
    finishes = finishes || (is_finished(status.state) && !is_finished(job->status.state));
  std::vector<Delivery> delivered;
  for (const auto& [key, tile] : change.tiles)
    if (tile.state == TileState::done && key.first->tiles[key.second].state != TileState::done)
      delivered.push_back({key.first->status.id, key.second, tile.result_lease_id});
  const Observed observed = observed_before(change);
  apply(change);
  const StoreTicket ticket = queue_write(std::move(work));
  tell_observer(observed, ticket);
  store_thread_.after(ticket, [this, touched = std::move(touched), what,
                               delivered = std::move(delivered)](const std::string& error) {
    if (error.empty()) return;
    // The store refused (a full disk, say). Every job the change was for fails and says
    // why, rather than workers retrying it forever; what it delivered is not stored.
    std::lock_guard lock(mutex_);
    for (const std::string& id : touched)
      if (JobEntry* job = find_job(id))
        fail_unstorable(*job, "cannot store " + what + ": " + error, delivered);
    ++refusals_;
  });
  // Those waiting for a job to finish hear of it once it is durable.
  if (finishes)
    store_thread_.after(ticket, [callbacks = finished_callbacks_](const std::string&) {
      for (const auto& callback : callbacks) callback();
    });
  return ticket;
}

StoreTicket Scheduler::queue_write(StoreThread::Work work) {
  last_write_ = store_thread_.write(std::move(work));
  return last_write_;
}

namespace {

// What the store keeps of tiles is their leases, results and failures (see StoredState):
// the rows one change writes, made under the lock from memory as it is before the change,
// and written on the store thread.
struct StoredRows {
  struct Upload {
    ResultRow row;
    std::vector<std::span<const float>> pixels;
  };
  std::vector<JobRow> jobs;
  std::vector<TileFailureRow> failures;
  std::vector<LeaseRow> leases;
  std::vector<std::string> leases_ended;
  std::vector<Upload> uploads;
  std::vector<std::int64_t> forgotten_results;
  std::vector<WorkerRow> workers;

  void write(Store& store) const {
    for (const JobRow& job : jobs) store.update_job(job);
    for (const TileFailureRow& failure : failures) store.put_tile_failure(failure);
    for (const LeaseRow& lease : leases) store.put_lease(lease);
    for (const std::string& lease_id : leases_ended) store.delete_lease(lease_id);
    for (const Upload& upload : uploads) store.insert_result(upload.row, upload.pixels);
    for (const std::int64_t id : forgotten_results) store.delete_result(id);
    for (const WorkerRow& worker : workers) store.upsert_worker(worker);
  }
};

// The tiles that join and leave one lease in a change.
struct LeaseMoves {
  const JobEntry* job = nullptr;
  std::string worker_id;  // of the tiles that join it
  std::vector<int> joined;
  std::vector<int> left;
};

// Each moved lease's row as it is after the change: its live tiles (`live_of`, before the
// change) less those that left, and those that joined; none when it owes nothing more.
void record_leases(std::map<std::string, LeaseMoves>& leases,
                   const std::function<const std::vector<int>*(const std::string&)>& live_of,
                   StoredRows& rows) {
  for (auto& [lease_id, moves] : leases) {
    LeaseRow row{lease_id, moves.job->status.id, moves.worker_id, {}};
    // Sorted, so that the lease's live tiles (up to max_lease_tiles) are each looked up in
    // it, not scanned against it, on every upload.
    std::sort(moves.left.begin(), moves.left.end());
    if (const std::vector<int>* live = live_of(lease_id)) {
      for (const int index : *live) {
        if (std::binary_search(moves.left.begin(), moves.left.end(), index)) continue;
        row.tiles.push_back(index);
        if (row.worker_id.empty()) row.worker_id = moves.job->tiles[index].worker_id;
      }
    }
    row.tiles.insert(row.tiles.end(), moves.joined.begin(), moves.joined.end());
    if (row.tiles.empty())
      rows.leases_ended.push_back(lease_id);
    else
      rows.leases.push_back(std::move(row));
  }
}

}  // namespace

StoreThread::Work Scheduler::record(const StagedChange& change) const {
  // The staged tiles are told apart by what changed in them, so that an operation writes
  // one row per lease and per upload it touches, however many tiles those hold.
  auto rows = std::make_shared<StoredRows>();
  std::map<std::string, LeaseMoves> leases;
  std::map<std::pair<const JobEntry*, std::string>, StoredRows::Upload> uploads;  // job, lease
  for (const auto& [job, status] : change.jobs) rows->jobs.push_back(job_row(status));
  for (const auto& [key, tile] : change.tiles) {
    const auto& [job, index] = key;
    const TileSlot& was = job->tiles[index];
    if (tile.attempts != was.attempts || tile.last_error != was.last_error)
      rows->failures.push_back({job->status.id, index, tile.attempts, tile.last_error});
    if (tile.lease_id != was.lease_id) {
      if (!was.lease_id.empty()) {
        LeaseMoves& moves = leases[was.lease_id];
        moves.job = job;
        moves.left.push_back(index);
      }
      if (!tile.lease_id.empty()) {
        LeaseMoves& moves = leases[tile.lease_id];
        moves.job = job;
        moves.worker_id = tile.worker_id;
        moves.joined.push_back(index);
      }
    }
    if (tile.state == TileState::done && was.state != TileState::done) {
      const auto pixels = change.pixels.find(key);
      if (pixels == change.pixels.end())
        throw std::logic_error("tile " + std::to_string(index) + " done without pixels");
      StoredRows::Upload& upload = uploads[{job, tile.result_lease_id}];
      upload.row.tiles.push_back(index);
      upload.row.rays.push_back(tile.rays);
      upload.row.worker_id = tile.worker_id;
      upload.pixels.push_back(pixels->second);
    }
  }
  record_leases(
      leases,
      [this](const std::string& lease_id) -> const std::vector<int>* {
        const auto it = leases_.find(lease_id);
        return it == leases_.end() ? nullptr : &it->second.live;
      },
      *rows);
  for (auto& [key, upload] : uploads) {
    upload.row.job_id = key.first->status.id;
    upload.row.lease_id = key.second;
    rows->uploads.push_back(std::move(upload));
  }
  rows->forgotten_results = change.forgotten_results;
  for (const auto& [worker, staged] : change.workers) rows->workers.push_back(worker_row(staged));
  return [rows](Store& store) { rows->write(store); };
}

void Scheduler::apply(StagedChange& change) {
  // Jobs before tiles: apply_job keeps the tile counters, which apply_tile then moves.
  for (auto& [job, status] : change.jobs) apply_job(*job, status);
  for (auto& [key, tile] : change.tiles) apply_tile(*key.first, key.second, std::move(tile));
  for (auto& [worker, staged] : change.workers) {
    present_workers_ += static_cast<int>(is_present(staged.info.state)) -
                        static_cast<int>(is_present(worker->info.state));
    *worker = std::move(staged);
    worker->persisted_seen_ms = worker->info.last_seen_ms;
  }
  change = StagedChange{};
}

void Scheduler::apply_job(JobEntry& job, const JobRecord& next) {
  const JobRecord& s = job.status;
  const JobState was = s.state;
  // Every job state change passes here: one log line each.
  if (next.state != s.state) {
    if (next.error.empty())
      spdlog::info("job {} ({}): {} -> {}", s.id, s.name, to_string(s.state),
                   to_string(next.state));
    else
      spdlog::info("job {} ({}): {} -> {}: {}", s.id, s.name, to_string(s.state),
                   to_string(next.state), next.error);
  }
  active_.erase({-s.priority, s.created_at_ms, s.id});
  JobRecord updated = next;
  updated.tiles_total = s.tiles_total;
  updated.tiles_done = s.tiles_done;
  updated.tiles_rendering = s.tiles_rendering;
  updated.health = s.health;  // changed in place only, never staged
  job.status = std::move(updated);
  if (hands_out_tiles(job.status.state))
    active_.insert({-job.status.priority, job.status.created_at_ms, job.status.id});
  // A canceled or failed job's partial image is read from the store from now on.
  // Its frames done so far keep their images.
  if ((job.status.state == JobState::failed || job.status.state == JobState::canceled) &&
      was != job.status.state)
    for (int slot = 0; slot < job.frame_count(); ++slot)
      if (job.frame_done.empty() || job.frame_done[slot] < job.tiles_per_frame)
        images_.ended(image_key(job, slot));
}

void Scheduler::apply_tile(JobEntry& job, int index, TileSlot next) {
  track_tile(job, index, -1);
  job.tiles[index] = std::move(next);
  track_tile(job, index, +1);
}

void Scheduler::track_tile(JobEntry& job, int index, int sign) {
  const TileSlot& tile = job.tiles[index];
  const int position = job.rank[index];
  const int slot = job.slot_of(index);
  if (tile.state != TileState::done && tile.attempts >= config_.max_tile_attempts) {
    const bool failed = job.frame_spent[slot] > 0;
    job.frame_spent[slot] += sign;
    if (failed != (job.frame_spent[slot] > 0)) set_frame_pending(job, slot, failed);
  }
  if (tile.state == TileState::pending) {
    if (sign < 0)
      job.pending.erase(position);
    else if (job.frame_spent[slot] == 0)
      job.pending.insert(position);
  }
  if (tile.state == TileState::done) {
    job.status.tiles_done += sign;
    job.frame_done[slot] += sign;
  }
  if (!tile.lease_id.empty()) {
    job.status.tiles_rendering += sign;
    job.frame_rendering[slot] += sign;
    index_lease_tile(tile.lease_id, job.status.id, index, sign, true, tile.lease_expires_ms);
  }
  if (!tile.result_lease_id.empty())
    index_lease_tile(tile.result_lease_id, job.status.id, index, sign, false);
  // The frame's own state follows from its counts: done, failed, or open.
  const bool done = job.frame_done[slot] == job.tiles_per_frame;
  const bool failed = !done && job.frame_spent[slot] > 0;
  const bool was_open = job.open_slots.contains(slot);
  const int number = job.status.frames->numbers[slot];
  std::vector<int>& failed_frames = job.status.failed_frames;
  const auto listed = std::lower_bound(failed_frames.begin(), failed_frames.end(), number);
  const bool was_failed = listed != failed_frames.end() && *listed == number;
  const bool was_done = !was_open && !was_failed;
  if (done != was_done) job.status.frames_done += done ? 1 : -1;
  if (failed && !was_failed) failed_frames.insert(listed, number);
  if (!failed && was_failed) failed_frames.erase(listed);
  if (!done && !failed)
    job.open_slots.insert(slot);
  else if (was_open)
    job.open_slots.erase(slot);
  if (job.open_slots.empty())
    job.status.current_frame.reset();
  else
    job.status.current_frame = job.status.frames->numbers[*job.open_slots.begin()];
}

void Scheduler::set_frame_pending(JobEntry& job, int slot, bool pending) {
  const int first = slot * job.tiles_per_frame;
  for (int index = first; index < first + job.tiles_per_frame; ++index) {
    if (job.tiles[index].state != TileState::pending) continue;
    if (pending)
      job.pending.insert(job.rank[index]);
    else
      job.pending.erase(job.rank[index]);
  }
}

void Scheduler::index_lease_tile(const std::string& lease_id, const std::string& job_id, int index,
                                 int sign, bool live, std::int64_t expires_ms) {
  if (sign > 0) {
    LeaseTiles& entry = leases_[lease_id];
    entry.job_id = job_id;
    if (!live) {
      entry.delivered += 1;
      return;
    }
    if (entry.live.empty() || entry.expires_ms != expires_ms) {
      if (!entry.live.empty()) expiries_.erase({entry.expires_ms, lease_id});
      entry.expires_ms = expires_ms;
      expiries_.emplace(expires_ms, lease_id);
    }
    entry.live.push_back(index);
    return;
  }
  const auto it = leases_.find(lease_id);
  if (it == leases_.end()) return;
  LeaseTiles& entry = it->second;
  if (!live) {
    entry.delivered -= 1;
  } else if (const auto found = std::find(entry.live.begin(), entry.live.end(), index);
             found != entry.live.end()) {
    *found = entry.live.back();  // the order is no matter
    entry.live.pop_back();
    if (entry.live.empty()) expiries_.erase({entry.expires_ms, lease_id});
  }
  if (entry.live.empty() && entry.delivered <= 0) leases_.erase(it);
}

void Scheduler::renew_lease(const std::string& lease_id, std::int64_t expires_ms) {
  const auto it = leases_.find(lease_id);
  if (it == leases_.end() || it->second.live.empty()) return;
  JobEntry& job = *jobs_.at(it->second.job_id);
  for (const int index : it->second.live) job.tiles[index].lease_expires_ms = expires_ms;
  if (it->second.expires_ms == expires_ms) return;
  expiries_.erase({it->second.expires_ms, lease_id});
  it->second.expires_ms = expires_ms;
  expiries_.emplace(expires_ms, lease_id);
}

void Scheduler::index_tiles(JobEntry& job, std::vector<int> order) {
  const int frames = job.frame_count();
  if (job.tiles_per_frame == 0) job.tiles_per_frame = static_cast<int>(job.tiles.size()) / frames;
  if (order.empty()) {
    order = hand_out_order(*job.rects, job.status.width, job.status.height, frames);
  }
  job.order = std::move(order);
  job.rank.assign(job.order.size(), 0);
  for (std::size_t position = 0; position < job.order.size(); ++position)
    job.rank[job.order[position]] = static_cast<int>(position);
  job.pending.reset(job.order.size());
  job.status.tiles_total = static_cast<int>(job.tiles.size());
  job.status.tiles_done = 0;
  job.status.tiles_rendering = 0;
  job.frame_done.assign(frames, 0);
  job.frame_rendering.assign(frames, 0);
  job.frame_spent.assign(frames, 0);
  job.open_slots.clear();
  job.status.frames_done = 0;
  job.status.failed_frames.clear();
  // Every frame is open until its tiles say otherwise; a frame without tiles (a job whose
  // stored size cannot be read) is neither, and fails the job at start-up.
  if (job.tiles_per_frame > 0)
    for (int slot = 0; slot < frames; ++slot) job.open_slots.insert(job.open_slots.end(), slot);
  for (int index = 0; index < job.status.tiles_total; ++index) track_tile(job, index, +1);
  if (job.status.tiles_total == 0) job.status.current_frame.reset();
  if (hands_out_tiles(job.status.state))
    active_.insert({-job.status.priority, job.status.created_at_ms, job.status.id});
}

}  // namespace tessera
