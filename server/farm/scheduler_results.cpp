// Results: an upload's tiles checked against their lease (fencing), stored, and handed to
// the job's image once durable.
#include <set>
#include <variant>

#include <spdlog/spdlog.h>

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"

namespace tessera {

std::optional<std::vector<TileResult>> slice_upload(std::span<const float> pixels,
                                                    std::span<const int> tiles,
                                                    std::span<const std::size_t> pixel_counts,
                                                    std::span<const std::uint64_t> rays) {
  std::vector<TileResult> results;
  results.reserve(tiles.size());
  std::size_t offset = 0;
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const std::size_t floats = pixel_counts[i] * 3;
    if (offset + floats > pixels.size()) return std::nullopt;
    results.push_back({tiles[i], pixels.subspan(offset, floats), rays[i]});
    offset += floats;
  }
  if (offset != pixels.size()) return std::nullopt;
  return results;
}

Pending<ResultOutcome> Scheduler::complete(const std::string& lease_id,
                                           std::span<const float> pixels, std::uint64_t rays) {
  std::vector<TileResult> results;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    const auto it = leases_.find(lease_id);
    if (it == leases_.end()) return pending(ResultOutcome::stale, before);
    if (it->second.live.empty())
      return pending(it->second.delivered == 0 ? ResultOutcome::stale : ResultOutcome::duplicate,
                     before);
    std::vector<int> tiles;
    std::vector<std::size_t> counts;
    for (const LeaseTileRecord& tile : lease_of(lease_id).tiles) {
      tiles.push_back(tile.index);
      counts.push_back(tile.rect.pixel_count());
    }
    std::vector<std::uint64_t> rays_each(tiles.size(), 0);
    rays_each.front() = rays;  // the count is the whole upload's, kept on its first tile
    auto sliced = slice_upload(pixels, tiles, counts, rays_each);
    if (!sliced) return pending(ResultOutcome::wrong_size, before);
    results = std::move(*sliced);
  }
  // Checked again under the lock: the lease may have moved on in between.
  return complete(lease_id, results);
}

Pending<ResultOutcome> Scheduler::complete(const std::string& lease_id,
                                           std::span<const TileResult> results) {
  std::lock_guard lock(mutex_);
  const StoreTicket before = last_write_;
  const auto it = leases_.find(lease_id);
  if (it == leases_.end()) return pending(ResultOutcome::stale, before);
  const std::vector<int> live = it->second.live;  // commit() rewrites the index
  JobEntry& job = *jobs_.at(it->second.job_id);

  std::set<int> named;
  const auto checked = fresh_results(job, lease_id, live, results, named);
  if (const auto* refused = std::get_if<ResultOutcome>(&checked)) return pending(*refused, before);
  const auto& fresh = std::get<std::vector<const TileResult*>>(checked);

  StagedChange change;
  const bool frame_done = stage_results(change, job, lease_id, fresh, live, named);
  const std::string image = image_key(job, job.slot_of(fresh.front()->tile_index));
  const StoreTicket ticket =
      commit(change, "the result of tile " + std::to_string(fresh.front()->tile_index));
  std::vector<std::pair<int, std::span<const float>>> tiles;
  for (const TileResult* result : fresh) tiles.emplace_back(result->tile_index, result->pixels);
  std::vector<FarmObserver::TileChange> done;
  if (observer_ && observer_->wants_tiles(job.status.id))
    for (const TileResult* result : fresh) {
      done.push_back(tile_change(job, result->tile_index));
      done.back().pixels = result->pixels;
    }
  store_thread_.after(ticket, [this, image, tiles = std::move(tiles), done = std::move(done),
                               frame_done](const std::string& error) {
    if (!error.empty()) return;
    images_.stored(image, tiles, frame_done);
    if (frame_done) images_.completed(image);
    // Before the answer's own callback, after which the pixels are gone.
    if (observer_ && !done.empty()) observer_->tiles_changed(done);
  });
  return pending(ResultOutcome::accepted, before);
}

std::variant<ResultOutcome, std::vector<const TileResult*>> Scheduler::fresh_results(
    const JobEntry& job, const std::string& lease_id, const std::vector<int>& live,
    std::span<const TileResult> results, std::set<int>& named) const {
  std::vector<const TileResult*> fresh;
  for (const TileResult& result : results) {
    if (!named.insert(result.tile_index).second) return ResultOutcome::wrong_tile;
    if (result.tile_index < 0 || result.tile_index >= static_cast<int>(job.tiles.size()))
      return live.empty() ? ResultOutcome::stale : ResultOutcome::wrong_tile;
    const TileSlot& tile = job.tiles[result.tile_index];
    if (tile.result_lease_id == lease_id) continue;  // a repeat: ignored
    // A live lease gives up tiles only by delivering them, so a tile it neither holds nor
    // delivered was never its own; a lease with no live tile left has ended.
    if (tile.lease_id != lease_id)
      return live.empty() ? ResultOutcome::stale : ResultOutcome::wrong_tile;
    if (result.pixels.size() != job.rect(result.tile_index).pixel_count() * 3)
      return ResultOutcome::wrong_size;
    fresh.push_back(&result);
  }
  if (fresh.empty()) return results.empty() ? ResultOutcome::wrong_size : ResultOutcome::duplicate;
  return fresh;
}

bool Scheduler::stage_results(StagedChange& change, JobEntry& job, const std::string& lease_id,
                              const std::vector<const TileResult*>& fresh,
                              const std::vector<int>& live, const std::set<int>& named) {
  const std::int64_t now = clock_.now_ms();
  JobRecord& status = change.job(job);
  for (const TileResult* result : fresh) {
    TileSlot& tile = change.tile(job, result->tile_index);
    tile.state = TileState::done;
    // Its lease's id, shared, now names its stored pixels; worker_id stays: who rendered it.
    tile.result_lease_id = std::move(tile.lease_id);
    tile.lease_id.clear();
    tile.lease_expires_ms = 0;
    tile.rays = result->rays;
    tile.render_us = result->render_us;
    change.pixels[{&job, result->tile_index}] = result->pixels;
    status.rays += result->rays;
    counters_.rays += result->rays;
    if (result->render_us > 0) counters_.tile_render_seconds.observe(result->render_us * 1e-6);
  }
  counters_.tiles_rendered += fresh.size();
  job.status.health.progress_at_ms = now;
  // A lease's tiles are of one frame, so the upload finishes that frame or none.
  const int slot = job.slot_of(fresh.front()->tile_index);
  const bool frame_done =
      job.frame_done[slot] + static_cast<int>(fresh.size()) == job.tiles_per_frame;
  if (frame_done && job.open_slots.size() == 1 && *job.open_slots.begin() == slot) {
    if (job.status.failed_frames.empty()) {
      status.state = JobState::completed;
      status.finished_at_ms = now;
    } else {
      stage_job_failure(change, job, failed_frames_error(job, {}, change));
    }
  }
  if (WorkerEntry* worker = find_worker(job.tiles[fresh.front()->tile_index].worker_id)) {
    WorkerEntry& staged = change.worker(*worker);
    staged.info.tiles_rendered += fresh.size();
    std::uint64_t rays = 0;
    for (const TileResult* result : fresh) rays += result->rays;
    // One entry per second at most: the entry is copied with the worker at every change.
    if (!staged.recent.empty() && std::get<0>(staged.recent.back()) / 1000 == now / 1000) {
      std::get<1>(staged.recent.back()) += static_cast<int>(fresh.size());
      std::get<2>(staged.recent.back()) += rays;
    } else {
      staged.recent.emplace_back(now, static_cast<int>(fresh.size()), rays);
    }
    while (!staged.recent.empty() && std::get<0>(staged.recent.front()) < now - 60'000)
      staged.recent.pop_front();
    staged.info.last_seen_ms = now;
    if (staged.lease_id == lease_id) {
      // The lease's next tile in hand-out order, if any is left.
      int next = -1;
      for (const int index : live)
        if (!named.contains(index) && (next < 0 || job.rank[index] < job.rank[next])) next = index;
      staged.info.current_tile = next;
      if (next < 0) {
        staged.lease_id.clear();
        staged.info.current_job.clear();
        staged.info.state = WorkerState::idle;
      }
    }
  }
  return frame_done;
}

std::optional<std::vector<std::size_t>> Scheduler::tile_pixel_counts(
    const std::string& lease_id, std::span<const std::uint64_t> tile_indexes) const {
  std::lock_guard lock(mutex_);
  const auto it = leases_.find(lease_id);
  if (it == leases_.end()) return std::nullopt;
  const JobEntry& job = *jobs_.at(it->second.job_id);
  std::vector<std::size_t> counts;
  counts.reserve(tile_indexes.size());
  for (const std::uint64_t index : tile_indexes)
    counts.push_back(index < job.tiles.size() ? job.rect(static_cast<int>(index)).pixel_count()
                                              : 0);
  return counts;
}

void Scheduler::note_refused_result(const std::string& lease_id, const std::string& why) {
  std::lock_guard lock(mutex_);
  const auto it = leases_.find(lease_id);
  if (it == leases_.end()) return;
  JobEntry& job = *jobs_.at(it->second.job_id);
  job.status.health.refused_results += 1;
  job.status.health.last_problem = "a result was refused: " + why;
}

}  // namespace tessera
