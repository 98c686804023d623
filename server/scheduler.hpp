// The coordinator's one state machine: jobs, their tiles, workers and the leases that
// bind a tile to a worker. Every state change happens here, under one lock, and is made
// durable in the Store before the call returns. Workers pull: claim() hands out the best
// pending tile; heartbeats keep a lease alive; a result is accepted only from the current
// holder of the tile's lease (fencing), and only once.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "common/image.hpp"
#include "common/scene.hpp"
#include "server/clock.hpp"
#include "server/store.hpp"

namespace tessera {

struct SchedulerConfig {
  std::int64_t lease_timeout_ms = 30'000;      // a lease expires this long after its last heartbeat
  std::int64_t heartbeat_interval_ms = 5'000;  // what workers are told to use
};

enum class JobState { queued, running, completed, failed, canceled };
const char* to_string(JobState state);
std::optional<JobState> job_state_from_string(std::string_view text);
inline bool is_finished(JobState s) {
  return s == JobState::completed || s == JobState::failed || s == JobState::canceled;
}

struct JobStatus {
  std::string id;
  std::string name;
  JobState state = JobState::queued;
  int priority = 50;
  int width = 0;
  int height = 0;
  int tile_size = 0;
  int tiles_total = 0;
  int tiles_done = 0;
  int tiles_rendering = 0;      // tiles under a live lease
  std::int64_t created_at_ms = 0;
  std::int64_t started_at_ms = 0;   // 0: not started
  std::int64_t finished_at_ms = 0;  // 0: not finished
  std::string error;                // set when failed
  std::uint64_t rays = 0;           // summed over the tiles done
  std::string scene_digest;         // hex SHA-256 of the scene JSON as stored
};

struct WorkerInfo {
  std::string id;
  std::string name;
  std::string host;
  int threads = 0;
  std::string state;  // "idle", "rendering", "gone"
  std::string current_job;         // empty when idle
  int current_tile = -1;
  std::uint64_t tiles_rendered = 0;
  std::int64_t last_seen_ms = 0;
};

struct Lease {
  std::string id;  // unique per grant: fencing token
  std::string job_id;
  std::string worker_id;
  int tile_index = 0;
  TileRect rect;
  std::string scene_digest;
  std::int64_t expires_at_ms = 0;
};

enum class ResultOutcome {
  accepted,    // stored; the tile is done
  duplicate,   // this lease already delivered; nothing changed
  stale,       // the lease expired, was withdrawn or given to another worker; refused
  wrong_size,  // pixel count does not match the tile; refused
};

enum class CancelOutcome { canceled, not_found, already_finished };
enum class RemoveOutcome { removed, not_found, not_finished };

// Defined in server/scheduler_entries.hpp; only the scheduler's sources need them.
struct JobEntry;
struct TileSlot;
struct WorkerEntry;
struct StagedChange;

class Scheduler {
 public:
  // Loads all state from `store` and reconciles it (see load_and_reconcile()).
  Scheduler(Store& store, const Clock& clock, SchedulerConfig config = {});
  ~Scheduler();

  const SchedulerConfig& config() const { return config_; }

  // --- jobs -----------------------------------------------------------------
  // `scene` is already validated; `scene_json` is what is stored and served to workers.
  JobStatus submit(const std::string& name, int priority, const Scene& scene,
                   const std::string& scene_json);
  std::optional<JobStatus> job(const std::string& id) const;
  // Newest first; `state` filters when set; at most `limit`.
  std::vector<JobStatus> jobs(std::optional<JobState> state, std::size_t limit) const;
  CancelOutcome cancel(const std::string& id);
  RemoveOutcome remove(const std::string& id);
  std::optional<std::string> scene_json(const std::string& digest) const;
  // The job's image from the tiles stored so far; missing tiles are black.
  std::optional<Image> assemble(const std::string& id) const;

  // --- workers --------------------------------------------------------------
  WorkerInfo register_worker(const std::string& name, const std::string& host, int threads);
  bool worker_known(const std::string& worker_id) const;
  // A worker that still holds a live lease gets that lease back (reconnect); otherwise the
  // best pending tile: highest priority job first, then oldest job, tiles centre-first.
  std::optional<Lease> claim(const std::string& worker_id);
  // Extends the lease; nothing when it is no longer the tile's current lease.
  std::optional<Lease> heartbeat(const std::string& lease_id);
  ResultOutcome complete(const std::string& lease_id, std::span<const float> pixels,
                         std::uint64_t rays);
  // The worker gives the tile back (for example on SIGTERM) without a result.
  void release(const std::string& lease_id);
  // Records that a worker is alive (any request from it).
  void touch_worker(const std::string& worker_id);
  void worker_left(const std::string& worker_id);
  std::vector<WorkerInfo> workers() const;

  // --- time -----------------------------------------------------------------
  // Returns expired leases' tiles to the queue. Call periodically.
  void expire_leases();
  // Called (outside the lock) whenever a tile may have become claimable.
  void on_work_available(std::function<void()> callback);

 private:
  struct TileRef {
    std::string job_id;
    int tile_index = 0;
  };
  using Callbacks = std::vector<std::function<void()>>;

  // Everything below runs with mutex_ held.
  void load_and_reconcile();
  JobEntry* find_job(const std::string& id) const;
  WorkerEntry* find_worker(const std::string& id) const;
  Image assemble_locked(const JobEntry& job) const;
  // Writes the completed job's image; a job whose image cannot be written fails.
  void finish_image(JobEntry& job);

  // The one way state changes: write `change` in one transaction, then apply it.
  void commit(StagedChange& change);
  void apply_job(JobEntry& job, const JobStatus& next);
  void apply_tile(JobEntry& job, int index, TileSlot next);
  // Adds (+1) or removes (-1) a tile's share of the indexes: pending set, counters,
  // leases_ and delivered_.
  void track_tile(JobEntry& job, int index, int sign);
  // Computes the tile order of a freshly built job and tracks all its tiles.
  void index_tiles(JobEntry& job);

  // Stages taking the lease off its tile and its worker; `expired` counts an attempt.
  void stage_lease_end(StagedChange& change, const std::string& lease_id, bool expired);
  // Returns the tiles of leases expired at `now` to the queue; true when there were any.
  bool expire_locked(std::int64_t now);
  Lease lease_of(const JobEntry& job, int index) const;
  std::string new_lease_id() const;
  // Records contact; persisted at most once per second per worker.
  void note_seen(WorkerEntry& worker, std::int64_t now);

  Store& store_;
  const Clock& clock_;
  SchedulerConfig config_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, std::unique_ptr<JobEntry>> jobs_;
  // Jobs that may hand out tiles, in claim order: (-priority, created_at, id).
  std::set<std::tuple<int, std::int64_t, std::string>> active_;
  std::unordered_map<std::string, TileRef> leases_;     // live lease id -> its tile
  std::unordered_map<std::string, TileRef> delivered_;  // lease id whose pixels are stored
  std::unordered_map<std::string, std::unique_ptr<WorkerEntry>> workers_;
  Callbacks callbacks_;
};

}  // namespace tessera
