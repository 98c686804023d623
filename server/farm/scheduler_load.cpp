// Start-up: the Scheduler's memory is rebuilt from the Store and made consistent again,
// whatever point of an operation the previous process stopped at. Afterwards every job
// that is not finished has a tile that is pending or under a lease that will expire, so
// no job can be stuck.
#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"

namespace tessera {
namespace {

void clear_lease(TileSlot& tile) {
  tile.lease_id.clear();
  tile.worker_id.clear();
  tile.lease_expires_ms = 0;
}

}  // namespace

void Scheduler::load_and_reconcile() {
  StoredState stored = store_.load();
  const std::int64_t now = clock_.now_ms();
  load_workers(stored.workers);
  const std::set<std::string> unknown_state = load_jobs(stored.jobs);
  for (TileFailureRow& row : stored.failures) {
    if (TileSlot* tile = stored_tile(row.job_id, row.tile_index)) {
      tile->attempts = row.attempts;
      tile->last_error = std::move(row.last_error);
    }
  }
  StagedChange change;
  load_results(stored.results, change);
  for (const LeaseRow& row : stored.leases) {
    const SharedText lease(row.id);
    const SharedText worker = worker_text(row.worker_id);
    for (const int index : row.tiles) {
      TileSlot* tile = stored_tile(row.job_id, index);
      if (!tile || tile->state == TileState::done) continue;  // delivered after all
      tile->state = TileState::leased;
      tile->lease_id = lease;
      tile->worker_id = worker;
    }
  }
  for (auto& [id, job] : jobs_) index_tiles(*job);
  recount_health(now);

  for (const std::string& id : unknown_state)
    change.job(*find_job(id)).error = "unknown state in the database";
  stage_leases_kept(change, now);
  stage_job_states(change, now);
  if (!change.empty()) commit(change);

  // A frame whose tiles are all done has its image, whatever became of its job; the
  // others' come from the store once the job has ended.
  std::vector<std::string> needs_image;
  for (const auto& [id, job] : jobs_) {
    const JobState state = job->status.state;
    const std::vector<std::shared_ptr<const Frame>> frames = frames_of(*job);
    for (int slot = 0; slot < job->frame_count(); ++slot) {
      const std::string key = image_key(*job, slot);
      const bool done = job->tiles_per_frame > 0 && job->frame_done[slot] == job->tiles_per_frame;
      images_.add(key, frames[slot],
                  done                 ? ImageAssembly::Stage::completed
                  : is_finished(state) ? ImageAssembly::Stage::ended
                                       : ImageAssembly::Stage::rendering);
      // The process stopped between the commit that finished it and the image's write.
      if (done && !images_.has_file(key)) needs_image.push_back(key);
    }
  }
  // Written by the image thread once what was reconciled is durable, which the
  // constructor waits for.
  for (const std::string& key : needs_image) images_.completed(key);
  std::set<std::string> kept;
  for (const auto& [id, job] : jobs_) kept.insert(id);
  queue_write([kept = std::move(kept)](Store& store) {
    store.prune_pixels([&](const std::string& job_id) { return kept.contains(job_id); });
  });
  images_.prune_files([this](const std::string& key) {
    const JobEntry* job = find_job(job_of_image(key));
    if (!job || job->tiles_per_frame == 0) return false;
    const std::optional<int> slot = slot_of_image(*job, key);
    return slot && job->frame_done[*slot] == job->tiles_per_frame;
  });
}

void Scheduler::load_workers(std::vector<WorkerRow>& rows) {
  for (WorkerRow& row : rows) {
    auto worker = std::make_unique<WorkerEntry>();
    worker->info.id = row.id;
    worker->id_text = row.id;
    worker->info.name = std::move(row.name);
    worker->info.host = std::move(row.host);
    worker->info.threads = row.threads;
    // A state this build does not know is one it cannot vouch for: gone until it calls.
    worker->info.state =
        protocol::value_in(protocol::kWorkerStateNames, row.state).value_or(WorkerState::gone);
    worker->info.tiles_rendered = row.tiles_rendered;
    worker->info.last_seen_ms = row.last_seen_ms;
    worker->info.draining = row.draining;
    worker->persisted_seen_ms = row.last_seen_ms;
    worker->secret_sha256 = std::move(row.secret_sha256);
    if (!worker->secret_sha256.empty()) secret_owners_[worker->secret_sha256] = row.id;
    present_workers_ += is_present(worker->info.state);
    workers_.emplace(row.id, std::move(worker));
  }
}

std::set<std::string> Scheduler::load_jobs(std::vector<JobRow>& rows) {
  std::set<std::string> unknown_state;
  for (JobRow& row : rows) {
    auto job = std::make_unique<JobEntry>();
    if (!status_from_row(std::move(row), job->status)) unknown_state.insert(job->status.id);
    const std::string id = job->status.id;
    jobs_.emplace(id, std::move(job));
  }

  // A job's tiles follow from its size and frames; each is pending unless the store says
  // otherwise. Oldest first, within the budget: a store that holds more than today's budget
  // (lowered since, or filled by an older release) must not keep the coordinator from
  // starting. A job that does not fit holds no tiles; an unfinished one fails, saying why.
  std::vector<JobEntry*> oldest_first;
  for (auto& [id, job] : jobs_) oldest_first.push_back(job.get());
  std::sort(oldest_first.begin(), oldest_first.end(), [](const JobEntry* a, const JobEntry* b) {
    return a->status.created_at_ms < b->status.created_at_ms;
  });
  for (JobEntry* job : oldest_first) {
    JobRecord& s = job->status;
    if (s.width <= 0 || s.height <= 0 || s.tile_size <= 0) continue;  // fails below: no tiles
    const std::uint64_t per_frame = tile_count(s.width, s.height, s.tile_size);
    const std::uint64_t count = per_frame * s.frames->numbers.size();
    std::optional<std::string> refusal;
    if (config_.max_job_tiles > 0 && count > config_.max_job_tiles)
      refusal = "its " + std::to_string(count) + " tiles are more than --max-job-tiles (" +
                std::to_string(config_.max_job_tiles) + ")";
    else
      refusal = job_memory_refusal(count);
    if (refusal) {
      spdlog::error("job {} ({}): not loaded at start: {}", s.id, s.name, *refusal);
      if (!is_finished(s.state)) not_loaded_[s.id] = "not loaded at start: " + *refusal;
      continue;
    }
    job->rects = std::make_shared<const std::vector<TileRect>>(
        split_into_tiles(s.width, s.height, s.tile_size));
    job->tiles_per_frame = static_cast<int>(job->rects->size());
    job->tiles.resize(job->rects->size() * s.frames->numbers.size());
    job_memory_ += job->tiles.size() * kTileBytes;
  }
  return unknown_state;
}

TileSlot* Scheduler::stored_tile(const std::string& job_id, int index) {
  JobEntry* job = find_job(job_id);  // the foreign keys rule out a row of no job
  if (!job || index < 0 || index >= static_cast<int>(job->tiles.size())) return nullptr;
  return &job->tiles[index];
}

void Scheduler::load_results(const std::vector<ResultRow>& rows, StagedChange& change) {
  // A result whose pixels are cut short, or that names a tile the job lacks or another
  // result delivered, cannot be assembled: it is forgotten, and its tiles render again.
  std::set<JobEntry*> rays_changed;
  std::vector<std::int64_t> forgotten_results;
  for (const ResultRow& row : rows) {
    JobEntry* job = find_job(row.job_id);
    std::int64_t bytes = 0;
    bool usable = job && !row.tiles.empty() && row.tiles.size() == row.rays.size();
    std::set<int> named;
    for (std::size_t i = 0; usable && i < row.tiles.size(); ++i) {
      const TileSlot* tile = stored_tile(row.job_id, row.tiles[i]);
      usable = tile && tile->state != TileState::done && named.insert(row.tiles[i]).second;
      if (usable)
        bytes +=
            static_cast<std::int64_t>(job->rect(row.tiles[i]).pixel_count() * 3 * sizeof(float));
    }
    if (!usable || bytes != row.pixel_bytes) {
      forgotten_results.push_back(row.id);
      if (job) {
        std::uint64_t rays = 0;
        for (const std::uint64_t r : row.rays) rays += r;
        job->status.rays -= std::min(job->status.rays, rays);
        rays_changed.insert(job);
      }
      continue;
    }
    const SharedText lease(row.lease_id);
    const SharedText worker = worker_text(row.worker_id);
    for (std::size_t i = 0; i < row.tiles.size(); ++i) {
      TileSlot& tile = job->tiles[row.tiles[i]];
      tile.state = TileState::done;
      tile.worker_id = worker;
      tile.rays = row.rays[i];
      tile.result_lease_id = lease;
    }
  }
  // Forgotten together with the rays they counted, in the one transaction of what follows.
  change.forgotten_results = std::move(forgotten_results);
  for (JobEntry* job : rays_changed) change.job(*job);
}

void Scheduler::recount_health(std::int64_t now) {
  // What the store keeps of a job's health: its tiles' failures and their last errors.
  for (auto& [id, job] : jobs_) {
    JobHealthRecord& health = job->status.health;
    for (std::size_t index = 0; index < job->tiles.size(); ++index) {
      const TileSlot& tile = job->tiles[index];
      health.tile_failures += tile.attempts;
      if (!tile.last_error.empty())
        health.last_problem = "tile " + std::to_string(index) + ": " + tile.last_error;
    }
    health.progress_at_ms = now;  // the stall clock starts again with the process
  }
}

void Scheduler::stage_leases_kept(StagedChange& change, std::int64_t now) {
  std::map<WorkerEntry*, std::string> holders;  // worker -> the one lease it keeps
  for (auto& [id, job_ptr] : jobs_) {
    JobEntry& job = *job_ptr;
    for (int index = 0; index < job.status.tiles_total; ++index) {
      const TileSlot& tile = job.tiles[index];
      if (tile.state != TileState::leased) {
        if (!tile.lease_id.empty()) clear_lease(change.tile(job, index));
        continue;
      }
      WorkerEntry* worker = find_worker(tile.worker_id);
      const auto held = worker ? holders.find(worker) : holders.end();
      if (tile.lease_id.empty() || is_finished(job.status.state) || !worker ||
          (held != holders.end() && held->second != tile.lease_id)) {
        TileSlot& reset = change.tile(job, index);
        reset.state = TileState::pending;
        clear_lease(reset);
        continue;
      }
      // The lease stands: its worker re-claims and gets it back, or it expires as usual.
      // Its clock restarts, since no heartbeat could reach a coordinator that was down;
      // every tile of it alike, as a lease has one expiry.
      if (tile.lease_expires_ms != now + config_.lease_timeout_ms)
        change.tile(job, index).lease_expires_ms = now + config_.lease_timeout_ms;
      WorkerEntry& staged = change.worker(*worker);
      if (held == holders.end() || job.rank[index] < job.rank[staged.info.current_tile]) {
        staged.info.current_job = job.status.id;
        staged.info.current_tile = index;
      }
      holders.emplace(worker, tile.lease_id);
      staged.lease_id = tile.lease_id;
      staged.info.state = WorkerState::rendering;
    }
  }
  // Without a lease we know nothing of a worker until it talks to us again.
  for (auto& [id, worker] : workers_)
    if (!holders.contains(worker.get()) && is_present(worker->info.state))
      change.worker(*worker).info.state = WorkerState::gone;
}

void Scheduler::stage_job_states(StagedChange& change, std::int64_t now) {
  for (auto& [id, job_ptr] : jobs_) {
    JobEntry& job = *job_ptr;
    int done = 0;
    bool touched = false;
    // Frames neither done nor failed, by the tiles as they are once reconciled.
    std::vector<int> open_done(job.frame_count(), 0);
    for (int index = 0; index < job.status.tiles_total; ++index) {
      const auto staged = change.tiles.find({&job, index});
      const TileState state =
          staged != change.tiles.end() ? staged->second.state : job.tiles[index].state;
      done += state == TileState::done;
      open_done[job.slot_of(index)] += state == TileState::done;
      touched = touched || state != TileState::pending;
    }
    bool open = false;
    for (int slot = 0; slot < job.frame_count() && job.tiles_per_frame > 0; ++slot)
      open = open || (open_done[slot] < job.tiles_per_frame && job.frame_spent[slot] == 0);
    const JobState state = job.status.state;
    if (!is_finished(state)) {
      if (job.status.tiles_total == 0) {
        JobRecord& s = change.job(job);
        s.state = JobState::failed;
        const auto reason = not_loaded_.find(id);
        s.error = reason != not_loaded_.end() ? reason->second : "the job has no tiles";
        s.finished_at_ms = now;
      } else if (done == job.status.tiles_total) {
        JobRecord& s = change.job(job);
        s.state = JobState::completed;
        if (s.finished_at_ms == 0) s.finished_at_ms = now;
      } else if (!open) {
        // Every frame is done or failed: the process stopped as the last one settled.
        stage_job_failure(change, job, failed_frames_error(job, {}, change));
      } else if (state == JobState::queued && touched) {
        JobRecord& s = change.job(job);
        s.state = JobState::running;
        if (s.started_at_ms == 0) s.started_at_ms = now;
      }
    } else if (state == JobState::completed && done != job.status.tiles_total) {
      JobRecord& s = change.job(job);
      s.state = JobState::running;
      s.finished_at_ms = 0;
      if (s.started_at_ms == 0) s.started_at_ms = now;
    }
  }
}

}  // namespace tessera
