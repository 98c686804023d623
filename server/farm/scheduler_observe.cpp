// What the FarmObserver hears: each committed change, as memory is once it is applied,
// told once it is durable, on the store thread.
#include <algorithm>

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"

namespace tessera {
namespace {

FarmObserver::TileView view_of(const TileSlot& tile) {
  if (tile.state == TileState::done) return FarmObserver::TileView::done;
  if (!tile.lease_id.empty()) return FarmObserver::TileView::rendering;
  return tile.attempts > 0 ? FarmObserver::TileView::failed : FarmObserver::TileView::pending;
}

}  // namespace

void Scheduler::observe(FarmObserver* observer) {
  std::lock_guard lock(mutex_);
  observer_ = observer;
}

std::optional<std::vector<FarmObserver::TileChange>> Scheduler::tiles(
    const std::string& job_id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(job_id);
  if (!job) return std::nullopt;
  std::vector<FarmObserver::TileChange> tiles;
  tiles.reserve(job->tiles.size());
  for (int index = 0; index < static_cast<int>(job->tiles.size()); ++index)
    tiles.push_back(tile_change(*job, index));
  return tiles;
}

std::optional<std::vector<FarmObserver::TileChange>> Scheduler::tiles(const std::string& job_id,
                                                                      std::size_t offset,
                                                                      std::size_t limit,
                                                                      std::size_t& total) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(job_id);
  if (!job) return std::nullopt;
  total = job->tiles.size();
  const std::size_t first = std::min(offset, total);
  const std::size_t end = first + std::min(limit, total - first);
  std::vector<FarmObserver::TileChange> tiles;
  tiles.reserve(end - first);
  for (std::size_t index = first; index < end; ++index)
    tiles.push_back(tile_change(*job, static_cast<int>(index)));
  return tiles;
}

FarmObserver::TileChange Scheduler::tile_change(const JobEntry& job, int index) const {
  const TileSlot& tile = job.tiles[index];
  FarmObserver::TileChange change;
  change.job_id = job.status.id;
  change.index = index;
  change.frame = job.frame_of_tile(index);
  change.rect = job.rect(index);
  change.view = view_of(tile);
  if (change.view == FarmObserver::TileView::rendering ||
      change.view == FarmObserver::TileView::done) {
    change.worker_id = tile.worker_id;
    if (const WorkerEntry* worker = find_worker(tile.worker_id))
      change.worker_name = worker->info.name;
  }
  change.render_us = tile.render_us;
  change.transfer = job.status.output_transfer;
  return change;
}

Scheduler::Observed Scheduler::observed_before(const StagedChange& change) const {
  Observed observed;
  if (!observer_) return observed;
  for (const auto& [job, status] : change.jobs) observed.jobs.push_back(job);
  const JobEntry* asked = nullptr;  // the job wants_tiles() was last asked of
  bool wanted = false;
  for (const auto& [key, tile] : change.tiles) {
    if (key.first != asked) {
      asked = key.first;
      wanted = observer_->wants_tiles(key.first->status.id);
    }
    // A tile done is told with its pixels, once they are stored (complete()).
    if (wanted && tile.state != TileState::done) observed.tiles.emplace_back(key.first, key.second);
    if (!change.jobs.contains(key.first) &&
        std::find(observed.jobs.begin(), observed.jobs.end(), key.first) == observed.jobs.end())
      observed.jobs.push_back(key.first);  // its counts move
  }
  for (const auto& [worker, staged] : change.workers)
    observed.workers.emplace_back(worker, worker->info.state);
  return observed;
}

void Scheduler::tell_observer(const Observed& observed, StoreTicket ticket) {
  if (!observer_) return;
  std::vector<JobRecord> jobs;
  for (const JobEntry* job : observed.jobs) jobs.push_back(job->status);
  std::vector<FarmObserver::TileChange> tiles;
  for (const auto& [job, index] : observed.tiles) tiles.push_back(tile_change(*job, index));
  std::vector<std::pair<WorkerRecord, FarmObserver::WorkerChange>> workers;
  for (const auto& [worker, was] : observed.workers) {
    const WorkerState now = worker->info.state;
    auto kind = FarmObserver::WorkerChange::changed;
    if (now == WorkerState::left && was != WorkerState::left)
      kind = FarmObserver::WorkerChange::left;
    else if (now == WorkerState::gone && was != WorkerState::gone)
      kind = FarmObserver::WorkerChange::lost;
    workers.emplace_back(worker->info, kind);
  }
  if (jobs.empty() && tiles.empty() && workers.empty()) return;
  store_thread_.after(ticket,
                      [observer = observer_, jobs = std::move(jobs), tiles = std::move(tiles),
                       workers = std::move(workers)](const std::string& error) {
                        if (!error.empty())
                          return;  // refused: its jobs fail, and that change is told
                        if (!tiles.empty()) observer->tiles_changed(tiles);
                        if (!jobs.empty()) observer->jobs_changed(jobs);
                        if (!workers.empty()) observer->workers_changed(workers);
                      });
}

}  // namespace tessera
