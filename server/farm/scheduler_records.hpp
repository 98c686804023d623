// What the Scheduler is configured with and answers with: its settings, the records of
// jobs, workers and leases it hands out, the outcomes of its calls, and Pending, the answer
// that may be given once its change is durable.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "common/image/image.hpp"
#include "common/protocol/events.hpp"
#include "common/protocol/job_state.hpp"
#include "common/protocol/jobs.hpp"
#include "common/protocol/limits.hpp"
#include "common/protocol/workers.hpp"
#include "common/scene/scene.hpp"
#include "server/farm/store_thread.hpp"
#include "server/metrics/histogram.hpp"

namespace tessera {

struct SchedulerConfig {
  std::int64_t lease_timeout_ms = 30'000;      // a lease expires this long after its last heartbeat
  std::int64_t heartbeat_interval_ms = 5'000;  // what workers are told to use
  int max_tile_attempts = 3;                   // a tile that fails this often fails its job
  // A worker that failed this often on a job gets no more of its tiles while another
  // worker could take them.
  int worker_failures_per_job = 2;
  // The most tiles a lease may owe at once (ProtocolLimits::max_lease_tiles, stated to
  // workers at registration): an extension adds no more than what keeps the lease within.
  int max_lease_tiles = ProtocolLimits{}.max_lease_tiles;
  // A tile handed out this often without its result being accepted fails its job: a worker
  // whose results are refused, or that drops its lease and claims it back, would otherwise
  // render the same tiles forever. Failures count against max_tile_attempts too; this
  // catches the loops that no failure reports.
  int max_tile_handouts = 10;
  // A running job whose tiles are being rendered but of which no tile has been delivered
  // for this long fails, saying so, instead of stalling unseen; 0: never.
  std::int64_t stall_timeout_ms = 30 * 60 * 1000;
  // A worker that left, or has not been heard from, for this long leaves the worker list
  // and the store; 0: never.
  std::int64_t forget_workers_after_ms = 60 * 60 * 1000;
  // What the jobs' tiles may cost the coordinator's memory together, as reckoned by
  // kTileBytes a tile, from submission until the job is removed; a submission past it is
  // refused, and a start finds the jobs past it failed, not loaded. 0: no limit.
  std::uint64_t job_memory_budget = std::uint64_t{2} << 30;
  // The most tiles of one job, every frame's: those of a 16384x16384 still at 8-pixel tiles.
  std::uint64_t max_job_tiles = (16384 / 8) * (16384 / 8);
};

// What one tile of a job costs the coordinator's memory, reckoned for job_memory_budget: its
// state, its place in the hand-out order and the pending set (docs/performance.md,
// "Coordinator memory per tile", measured 105 to 115 bytes).
inline constexpr std::uint64_t kTileBytes = 128;

// Signs of trouble on a job that has not (yet) failed of them, shown with its status: a farm
// that renders the same tiles again and again, or delivers nothing, must be seen as such.
// Kept in memory; tile_failures and last_problem are recounted from the stored tiles after
// a restart.
struct JobHealthRecord {
  int tile_failures = 0;    // failures charged to its tiles: expired leases, errors reported
  int refused_results = 0;  // results the coordinator refused for a reason other than a lost lease
  int repeated_handouts = 0;  // times one of its tiles went out again after going out before
  std::string last_problem;   // the latest of those, in words; "" when none
  // When a tile was last delivered, or rendering began (again) after none was under lease.
  std::int64_t progress_at_ms = 0;
};

// The frames a job renders, fixed at submit and shared by every copy of its status.
struct JobFrames {
  std::vector<int> numbers;  // the scene's frame numbers, ascending: the order they go out
  std::string list;          // as a frame list (format_frame_list); "" for a still
  bool animated() const { return !list.empty(); }
};
// A still's frames: the one frame 0.
std::shared_ptr<const JobFrames> still_frames();

struct JobRecord {
  std::string id;
  std::string name;
  JobState state = JobState::queued;
  int priority = 50;
  int width = 0;
  int height = 0;
  int tile_size = 0;
  int tiles_total = 0;
  int tiles_done = 0;
  int tiles_rendering = 0;  // tiles under a live lease
  std::int64_t created_at_ms = 0;
  std::int64_t started_at_ms = 0;                         // 0: not started
  std::int64_t finished_at_ms = 0;                        // 0: not finished
  std::string error;                                      // set when failed
  std::uint64_t rays = 0;                                 // summed over the tiles done
  std::string scene_digest;                               // hex SHA-256 of the scene JSON as stored
  OutputTransfer output_transfer = OutputTransfer::srgb;  // the scene's, for downloads
  JobHealthRecord health;  // in memory; only the Scheduler changes it, in place
  // Its tiles are every frame's, frame after frame: tiles_total is frames times the tiles
  // of one frame. Never null once the job exists.
  std::shared_ptr<const JobFrames> frames = still_frames();
  // Kept current with the tiles, by Scheduler::track_tile: frames whose every tile is done;
  // frames of which a tile failed for good (its attempts spent), by number, ascending; and
  // the first frame that is neither (none when every frame is one or the other).
  int frames_done = 0;
  std::vector<int> failed_frames;
  std::optional<int> current_frame;
};

using protocol::WorkerState;

struct WorkerRecord {
  std::string id;
  std::string name;
  std::string host;
  int threads = 0;
  WorkerState state = WorkerState::idle;
  std::string current_job;  // empty when idle
  int current_tile = -1;
  std::uint64_t tiles_rendered = 0;
  std::int64_t last_seen_ms = 0;
  bool draining = false;  // finishes the lease it holds and is given no more
  // Over the last minute (Scheduler::workers()).
  double tiles_per_min = 0;
  double rays_per_s = 0;
};

struct LeaseTileRecord {
  int index = 0;
  TileRect rect;
};

// One frame of a job, for GET /v1/jobs/{id}/frames.
struct FrameRecord {
  int frame = 0;
  protocol::FrameState state = protocol::FrameState::pending;
  int tiles_total = 0;
  int tiles_done = 0;
  int tiles_rendering = 0;
  std::string error;  // failed: its failed tile's last error
};

// A lease binds a batch of one or more tiles of one job to one worker. Its id is the
// fencing token: a tile's pixels are accepted only under the lease it is currently bound
// to. Tiles leave the lease one by one as their results arrive; the lease ends when none
// is left, or all at once when it expires, is released or its job is canceled.
struct LeaseRecord {
  std::string id;  // unique per grant
  std::string job_id;
  std::string worker_id;
  std::vector<LeaseTileRecord> tiles;  // the tiles still owed, in hand-out order
  std::string scene_digest;
  int frame = 0;  // the scene's frame all its tiles are of: a lease never spans two
  std::int64_t expires_at_ms = 0;
};

// One tile's result within an upload.
struct TileResult {
  int tile_index = 0;
  std::span<const float> pixels;  // float32 RGB, rows from the top
  std::uint64_t rays = 0;
  std::uint64_t render_us = 0;  // as its worker timed it; 0: not said
};

// An upload's body cut into its tiles, in order: pixel_counts[i] pixels of tiles[i], which
// took rays[i] rays. Nothing when the pixels are not exactly those tiles. The one place an
// upload is sliced, whether it names its tiles or sends every tile its lease owes.
std::optional<std::vector<TileResult>> slice_upload(std::span<const float> pixels,
                                                    std::span<const int> tiles,
                                                    std::span<const std::size_t> pixel_counts,
                                                    std::span<const std::uint64_t> rays);

enum class ResultOutcome {
  accepted,    // stored; the tiles are done (some may have been delivered already)
  duplicate,   // every tile was already delivered under this lease; nothing changed
  stale,       // the lease expired, was withdrawn or given to another worker; refused
  wrong_size,  // pixel count does not match a tile; refused
  wrong_tile,  // a tile that this lease never held, or named twice; refused
  unstored,    // the store could not take the pixels (a full disk); the job has failed
};

// An answer known at once, to be given once the change it reports is durable
// (Scheduler::when_stored). `ticket` is the last write queued when the answer was made:
// its own when it wrote something (`wrote`), else the one that holds what it reports.
template <class T>
struct Pending {
  T value{};
  StoreTicket ticket = 0;
  bool wrote = false;
};
using Written = Pending<std::monostate>;

// What the farm has done since the coordinator started, for GET /metrics: counted as it
// happens, read without the scheduler's lock.
struct FarmCounters {
  std::atomic<std::uint64_t> tiles_rendered{0};  // results accepted, a tile each
  std::atomic<std::uint64_t> rays{0};            // of those tiles
  std::atomic<std::uint64_t> lease_expiries{0};  // leases that ran out without a heartbeat
  std::atomic<std::uint64_t> tile_retries{0};    // tiles that went out again after going out
  // Each tile's render time on its worker, from 1 ms to 10 min.
  Histogram tile_render_seconds{
      {0.001, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 120, 300, 600}};
};

// The farm as it is now, for GET /metrics.
struct FarmGauges {
  std::map<JobState, int> jobs;  // every state, those with no job at 0
  // Tiles waiting for a worker, by their job's priority: of jobs that hand out tiles (not
  // paused ones). The queue depth that autoscaling follows.
  std::map<int, std::uint64_t> pending_by_priority;
  // idle, rendering, gone and left by their state; those of them that are draining also
  // under "draining".
  std::map<std::string, int> workers;
};

// What the scheduler reports of its changes, for the coordinator's event streams: each
// call comes on the store thread once its change is durable, in the order the changes
// were made. It may call the scheduler's const reads, and nothing else of it.
class FarmObserver {
 public:
  virtual ~FarmObserver() = default;
  // Each job's status after a change to it (its state, priority, tiles or rays).
  virtual void jobs_changed(const std::vector<JobRecord>& jobs) = 0;
  using TileView = protocol::TileView;
  struct TileChange {
    std::string job_id;
    int index = 0;
    int frame = 0;  // the scene's frame it is of
    TileRect rect;
    TileView view = TileView::pending;
    std::string worker_id;          // rendering: its worker; done: who rendered it
    std::string worker_name;        // of worker_id
    std::uint64_t render_us = 0;    // done: as its worker timed it
    std::span<const float> pixels;  // done: float32 RGB; valid during the call only
    OutputTransfer transfer = OutputTransfer::srgb;  // how the job's images are encoded
  };
  virtual void tiles_changed(const std::vector<TileChange>& tiles) = 0;
  // Whether anyone follows the tiles of `job_id` now: tile changes are recorded only then,
  // since a farm renders thousands of tiles a second that nobody may be watching. Called
  // under the scheduler's lock: it must be quick and must not call the scheduler.
  virtual bool wants_tiles(const std::string& job_id) = 0;
  using WorkerChange = protocol::WorkerChange;
  virtual void workers_changed(
      const std::vector<std::pair<WorkerRecord, WorkerChange>>& workers) = 0;
  virtual void job_removed(const std::string& job_id) = 0;
};

enum class CancelOutcome { canceled, not_found, already_finished };

// What a farm control (priority, pause, resume, retry, drain, removal) did: done, or
// refused for the reason the API's 409 gives (`code`, `message`).
struct ControlOutcome {
  enum class Result { done, not_found, refused };
  Result result = Result::done;
  std::string code;
  std::string message;
};
enum class RemoveOutcome { removed, not_found, not_finished };

}  // namespace tessera
