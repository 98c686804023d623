// A lease's tiles: rendered with every thread, handed to the uploads as they finish, and
// the lease ended as what happened says: delivered, refused, lost, failed or given back.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <sstream>

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include "worker/worker_daemon.hpp"

namespace tessera {
namespace {

// The last tiles of a lease, this many per thread, go up without waiting to be gathered:
// the next claim waits on their upload, and with nothing left to render no later tile
// would share their group.
constexpr int kPromptTilesPerThread = 4;
// More tiles are asked for no later than when this many per thread are left to take,
constexpr int kExtendTilesLeftPerThread = 2;
// or, sooner, while those left would keep every thread busy for this long: a few round
// trips of an extension. Small tiles go fast: at 8 pixels, 16 threads take the 64 tiles a
// quarter batch leaves in well under a millisecond, less than the answer takes to come.
constexpr double kAskAheadSeconds = 0.02;

}  // namespace

void WorkerDaemon::render(const Claimed& lease) {
  const Renderer& renderer = renderer_for(lease.scene_digest, lease.frame);
  uploading_lease_ = lease.lease_id;  // uploads_ is idle between leases
  heartbeat_->begin(lease.lease_id);
  LeaseProgress progress;
  const int fewest_left = kExtendTilesLeftPerThread * options_.threads;
  const auto least_left = [&] {
    const double per_tile = progress.seconds_per_tile(tile_thread_seconds_);
    if (per_tile <= 0) return fewest_left;
    const double ahead = kAskAheadSeconds * options_.threads / per_tile;
    // At most half of what a lease may owe, so that the answer has room to add.
    return std::clamp(static_cast<int>(ahead), fewest_left,
                      std::max(fewest_left, limits_.max_lease_tiles / 2));
  };
  BatchTiles tiles(lease.tiles, least_left, kPromptTilesPerThread * options_.threads, [&] {
    return extend(lease.lease_id, progress.seconds_per_tile(tile_thread_seconds_));
  });
  const auto start = std::chrono::steady_clock::now();
  if (options_.threads == 1) {
    render_tiles(renderer, tiles, progress);
  } else {
    arena_->execute([&] {
      tbb::parallel_for(
          0, options_.threads, [&](int) { render_tiles(renderer, tiles, progress); },
          tbb::simple_partitioner());
    });
  }
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  // No more tiles once the threads are done: an extension on its way is waited for, and
  // the tiles it added count as owed (released below when stopping).
  tiles.finish();
  const int count = tiles.count();
  const bool delivered = uploads_->flush();
  const bool kept = heartbeat_->end();
  if (progress.rendered == count && !stop_) {
    // Tiles of another scene may cost anything: start that estimate afresh.
    if (lease.scene_digest != timed_scene_) tile_thread_seconds_ = 0;
    timed_scene_ = lease.scene_digest;
    const double per_tile = took.count() * options_.threads / count;
    tile_thread_seconds_ =
        tile_thread_seconds_ > 0 ? 0.5 * (tile_thread_seconds_ + per_tile) : per_tile;
  }
  end_lease(lease, progress, count, delivered && kept);
}

void WorkerDaemon::render_tiles(const Renderer& renderer, BatchTiles& tiles,
                                LeaseProgress& progress) {
  // Each thread takes the next tile in the lease's (centre-first) order until none is
  // left, or the lease is lost, or a tile failed, or the worker is asked to stop.
  while (!stop_ && !heartbeat_->lost() && !uploads_->refused()) {
    const auto taken = tiles.take();
    if (!taken) return;
    if (taken->among_last) uploads_->send_promptly();
    const ClaimedTile& tile = taken->tile;
    const auto tile_start = std::chrono::steady_clock::now();
    try {
      inject_fault(tile.index);
      FinishedTile finished{tile.index, std::vector<float>(tile.rect.pixel_count() * 3), 0};
      finished.rays = renderer.render_tile(tile.rect, finished.pixels).total();
      finished.render_us =
          static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                         std::chrono::steady_clock::now() - tile_start)
                                         .count());
      uploads_->push(std::move(finished));
    } catch (const std::exception& e) {
      std::lock_guard lock(progress.failure_mutex);
      if (!progress.failure) progress.failure.emplace(tile.index, e.what());
      tiles.close();  // the others finish their tiles and take no more
      return;
    }
    progress.busy_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::steady_clock::now() - tile_start)
                            .count();
    ++progress.rendered;
    ++tiles_rendered_;
  }
}

void WorkerDaemon::end_lease(const Claimed& lease, const LeaseProgress& progress, int count,
                             bool still_held) {
  if (const auto refusal = take_refusal()) {
    // Not a lost lease: the coordinator refused what this worker sent. Rendering the tiles
    // again would be refused again, so the tile is reported as failed, which the
    // coordinator counts and shows on the job (and fails the job at its limit), and the
    // rest of the lease goes back.
    report_failure(lease.lease_id, refusal->first, refusal->second);
    return;
  }
  if (!still_held) {
    spdlog::info("lease {} was withdrawn; dropping the rest of its tiles of job {}", lease.lease_id,
                 lease.job_id);
    return;
  }
  if (progress.failure) {
    const auto& [tile, error] = *progress.failure;
    spdlog::error("tile {} of job {} failed: {}", tile, lease.job_id, error);
    report_failure(lease.lease_id, tile, error);  // gives back the rest too
    return;
  }
  if (progress.rendered < count) release(lease.lease_id);  // stopping: give back the rest
}

std::optional<std::pair<int, std::string>> WorkerDaemon::take_refusal() {
  std::lock_guard lock(refusal_mutex_);
  return std::exchange(refusal_, std::nullopt);
}

void WorkerDaemon::inject_fault(int tile_index) const {
  if (options_.fault.empty()) return;
  const auto colon = options_.fault.find(':');
  if (colon == std::string::npos) return;
  // "KIND:N" or "KIND:N,M,...": the tiles it applies to.
  bool listed = false;
  std::stringstream tiles(options_.fault.substr(colon + 1));
  for (std::string item; std::getline(tiles, item, ',');)
    listed = listed || (!item.empty() && std::stoi(item) == tile_index);
  if (!listed) return;
  const std::string kind = options_.fault.substr(0, colon);
  if (kind == "crash") {
    spdlog::error("fault injection: crashing on tile {}", tile_index);
    std::abort();
  }
  if (kind == "error")
    throw std::runtime_error("fault injection: error on tile " + std::to_string(tile_index));
}

}  // namespace tessera
