// The Scheduler's in-memory records and the staged changes that move them. Private to
// the scheduler's sources.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "common/protocol/workers.hpp"
#include "server/farm/pending_tiles.hpp"
#include "server/farm/scheduler.hpp"
#include "server/farm/shared_text.hpp"
#include "server/farm/store.hpp"

namespace tessera {

enum class TileState : std::uint8_t { pending, leased, done };
const char* to_string(TileState state);
std::optional<TileState> tile_state_from_string(std::string_view text);

// Idle or rendering: counted among the workers that share a job's tiles.
inline bool is_present(WorkerState state) {
  return state != WorkerState::gone && state != WorkerState::left;
}

// A tile's state. A job holds one per tile of every frame, millions of them for a large
// one, so it is kept small (72 bytes): its rectangle is the job's (JobEntry::rect), and
// its ids are shared with the lease and worker that every other tile of theirs names.
struct TileSlot {
  SharedText lease_id;         // the live lease; "" when none
  SharedText worker_id;        // the lease holder, or who rendered a done tile
  SharedText result_lease_id;  // the lease whose pixels are stored
  SharedText last_error;       // why it failed last
  std::int64_t lease_expires_ms = 0;
  std::uint64_t rays = 0;
  std::uint64_t render_us = 0;  // of a done tile, as its worker timed it; in memory only
  int attempts = 0;  // times it failed: its lease expired, or its worker reported an error
  int handouts = 0;  // times it went out under a lease; in memory only (see count_handouts)
  TileState state = TileState::pending;
};
static_assert(sizeof(TileSlot) <= 72, "a tile's state is kept small: see TileSlot");

struct JobEntry {
  JobRecord status;  // tiles_total/done/rendering are kept current by Scheduler::track_tile
  // Every frame's tiles, frame after frame: frame slot k (status.frames->numbers[k]) holds
  // indexes k * tiles_per_frame to (k + 1) * tiles_per_frame - 1, cut alike.
  std::vector<TileSlot> tiles;
  int tiles_per_frame = 0;
  // One frame's rectangles, by index in the frame: every frame is cut alike.
  // Empty for a job that holds no tiles (not loaded at start).
  std::shared_ptr<const std::vector<TileRect>> rects =
      std::make_shared<const std::vector<TileRect>>();
  const TileRect& rect(int index) const { return (*rects)[index % tiles_per_frame]; }
  int slot_of(int index) const { return index / tiles_per_frame; }
  int frame_of_tile(int index) const { return status.frames->numbers[slot_of(index)]; }
  int frame_count() const { return static_cast<int>(status.frames->numbers.size()); }
  // Per frame slot, kept by Scheduler::track_tile: its tiles done, under a live lease, and
  // spent (not done, their attempts used up: the frame has failed while it has any).
  std::vector<int> frame_done;
  std::vector<int> frame_rendering;
  std::vector<int> frame_spent;
  std::set<int> open_slots;  // the slots neither done nor failed
  std::vector<int> order;    // position in hand-out order -> tile index (centre-first)
  std::vector<int> rank;     // tile index -> position
  PendingTiles pending;      // positions of pending tiles; the first is handed out next
  // Failures on this job by worker, as "name@host" so that a restarted worker process is
  // still the same worker; in memory only.
  std::map<std::string, int> failures_by_worker;
};

struct WorkerEntry {
  std::string key() const { return info.name + "@" + info.host; }

  WorkerRecord info;                   // current_job/current_tile mirror lease_id
  SharedText id_text;                  // info.id, shared by the tiles that name it
  std::string lease_id;                // the live lease it holds; "" when none
  std::int64_t persisted_seen_ms = 0;  // last_seen as last written to the store
  std::string secret_sha256;           // of the secret its registration gave it
  // Its accepted uploads of the last minute, a second per entry: (when, tiles, rays); in
  // memory only.
  std::deque<std::tuple<std::int64_t, int, std::uint64_t>> recent;
};

// New values for records, gathered by one operation. Scheduler::commit writes them in one
// transaction and only then applies them, so memory never runs ahead of the database.
// Staging a record again returns the same copy.
struct StagedChange {
  TileSlot& tile(JobEntry& job, int index);
  JobRecord& job(JobEntry& job);
  WorkerEntry& worker(WorkerEntry& worker);
  bool empty() const {
    return tiles.empty() && jobs.empty() && workers.empty() && forgotten_results.empty();
  }

  std::map<std::pair<JobEntry*, int>, TileSlot> tiles;
  std::map<JobEntry*, JobRecord> jobs;
  std::map<WorkerEntry*, WorkerEntry> workers;
  // Results, stored with the tile they belong to.
  std::map<std::pair<const JobEntry*, int>, std::span<const float>> pixels;
  // Stored results to delete (load_and_reconcile() found them unusable).
  std::vector<std::int64_t> forgotten_results;
  // Frame slots of an animation that fail in this change (a tile spent its attempts): in
  // memory they follow from the tiles once applied; staged, later failures see them here.
  std::map<const JobEntry*, std::set<int>> failing_slots;
};

// A job's status and its stored row, each from the other: the one mapping between them.
JobRow job_row(const JobRecord& status);
// False when the row's state is not one this build knows (the job is then failed).
bool status_from_row(JobRow&& row, JobRecord& status);
WorkerRow worker_row(const WorkerEntry& worker);
// The images of the job, for ImageAssembly: one per frame slot, each under its
// image_key().
std::vector<std::shared_ptr<const Frame>> frames_of(const JobEntry& job);
// What a frame's image is known by: a still's (or a one-frame job's) by the job's id, an
// animation's frames by the id and the frame number ("j-....f12").
std::string image_key(const JobEntry& job, int slot);
// Why a tile that spent its attempts failed, `index` counted in its frame: "tile 4 at
// (32, 32) failed 3 times; the last error: ...". A still's job error, an animation's
// frame's.
std::string spent_tile_error(int index, const TileRect& rect, const TileSlot& tile);
// The job id of an image key, and the frame slot it names in `job` (nothing for a key
// that is not one of the job's).
std::string job_of_image(const std::string& key);
std::optional<int> slot_of_image(const JobEntry& job, const std::string& key);
// The tiles a job of `frames` frames of `rects` has, in hand-out order: frames in order,
// each frame's centre first.
std::vector<int> hand_out_order(const std::vector<TileRect>& rects, int width, int height,
                                int frames);

}  // namespace tessera
