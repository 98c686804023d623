// The coordinator's one state machine: jobs, their tiles, workers and the leases that
// bind a tile to a worker. Every state change happens here, under one lock, in memory, and
// is queued for the store thread (StoreThread) as it is made; a call returns its answer at
// once as a Pending, which its caller gives only once when_stored() says the change is
// durable. The network's threads thus never wait on the disk, and nobody hears of a change
// that a crash could undo. Workers pull: claim() hands out the best pending tile;
// heartbeats keep a lease alive; a result is accepted only from the current holder of the
// tile's lease (fencing), and only once.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <unordered_map>
#include <variant>
#include <vector>

#include "common/image/image.hpp"
#include "common/scene/scene.hpp"
#include "server/farm/clock.hpp"
#include "server/farm/image_assembly.hpp"
#include "server/farm/scheduler_records.hpp"
#include "server/farm/shared_text.hpp"
#include "server/farm/store.hpp"
#include "server/farm/store_thread.hpp"

namespace tessera {

// Defined in server/farm/scheduler_entries.hpp; only the scheduler's sources need them.
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
  // Called on the store thread once the job is stored, with its status, or with nothing
  // and the store's error when the store refused it.
  using Submitted = std::function<void(std::optional<JobRecord>, const std::string& error)>;
  // `scene` is already validated; `scene_json` is what is stored and served to workers. The
  // job exists, for every other call too, once it is stored.
  // `frames`: the frames of an animated scene to render, ascending (checked against its
  // range); empty for a still, its one frame 0.
  void submit(const std::string& name, int priority, const Scene& scene, std::string scene_json,
              Submitted then, std::vector<int> frames = {});
  std::optional<JobRecord> job(const std::string& id) const;
  // Newest first; `state` filters when set; at most `limit`, after the first `offset`.
  std::vector<JobRecord> jobs(std::optional<JobState> state, std::size_t limit,
                              std::size_t offset = 0,
                              const std::optional<std::string>& name = std::nullopt) const;
  Pending<CancelOutcome> cancel(const std::string& id);
  Pending<RemoveOutcome> remove(const std::string& id);
  // Farm controls (scheduler_controls.cpp). A new priority takes effect at the next claim
  // or extension; a job that is not finished may change it.
  Pending<ControlOutcome> set_priority(const std::string& id, int priority);
  // A queued or running job hands out no more tiles: the leases out now run out (their
  // tiles are delivered or go back to the queue), and nothing is withdrawn. Pausing a
  // paused job does nothing.
  Pending<ControlOutcome> pause(const std::string& id);
  // A paused job hands out tiles again: running when it had begun, queued otherwise.
  // Resuming a job that is not paused does nothing, unless it has finished (refused).
  Pending<ControlOutcome> resume(const std::string& id);
  // A failed job renders its tiles that are not done again: their failures are forgotten
  // and the job is running (or queued) once more, with the tiles it had kept.
  Pending<ControlOutcome> retry(const std::string& id);
  // The ids of the jobs that begin with `prefix`, at most `limit`, in id order.
  std::vector<std::string> job_ids_with_prefix(const std::string& prefix, std::size_t limit) const;
  // The scene stored under `digest`, read on the store thread and handed to `then` there.
  void scene_json(const std::string& digest,
                  std::function<void(std::optional<std::string>)> then) const;
  // The job's image from the tiles stored so far; missing tiles are black. A running job
  // keeps its image in memory as tiles arrive, until its image file is written, so that
  // previews and the download right after completion need not read every tile back.
  // `then` gets it, on this thread from the canvas or on the store thread from the store;
  // null when there is no such job.
  void assemble(const std::string& id,
                std::function<void(std::shared_ptr<const Image>)> then) const;
  // The image file of a completed job, once the image thread has written it.
  std::optional<std::filesystem::path> image_file(const std::string& id) const;
  // The same for one frame of the job, by the scene's frame number: `assemble` hands over
  // null for a frame the job does not render, and `image_file` nothing until it is done.
  void assemble_frame(const std::string& id, int frame,
                      std::function<void(std::shared_ptr<const Image>)> then) const;
  std::optional<std::filesystem::path> frame_image_file(const std::string& id, int frame) const;
  // Every frame of the job, in the order they go out; nothing when there is no such job.
  std::optional<std::vector<FrameRecord>> frames(const std::string& id) const;
  // One frame of the job; nothing when there is no such job or frame.
  std::optional<FrameRecord> frame(const std::string& id, int frame) const;
  // Waits until the image file of every job completed so far is written (or has failed).
  void wait_for_images();

  // --- durability -------------------------------------------------------------
  // Calls `done` on the store thread once `pending`'s answer may be given: with "" when
  // what it reports is durable, or with the store's error when its own change was refused
  // (the change's jobs have failed, saying why).
  template <class T>
  void when_stored(const Pending<T>& pending, StoreThread::Done done) {
    when_stored(pending.ticket, pending.wrote, std::move(done));
  }
  void when_stored(StoreTicket ticket, bool wrote, StoreThread::Done done);
  // As when_stored(), waiting; for threads that may wait on the disk (never the network's).
  std::string wait_stored(StoreTicket ticket, bool wrote);
  // For an answer that reports memory as it is now (a job's status): once this is durable,
  // so is everything the answer says, and a crash cannot take it back, unless the store
  // refused a change meanwhile, which refusals() counts.
  Written durable() const;
  // Changes the store has refused so far; each has failed its jobs in memory by the time
  // it is counted.
  std::uint64_t refusals() const { return refusals_.load(); }

  // --- workers --------------------------------------------------------------
  // `secret_sha256`: the digest of the secret the worker was given, which its later calls
  // prove (worker_with_secret()).
  Pending<WorkerRecord> register_worker(const std::string& name, const std::string& host,
                                        int threads, const std::string& secret_sha256 = "");
  bool worker_known(const std::string& worker_id) const;
  // The worker whose secret has this digest, while it has not left; nothing otherwise.
  std::optional<std::string> worker_with_secret(const std::string& secret_sha256) const;
  // The worker that holds the lease, while the lease is live; nothing otherwise.
  std::optional<std::string> lease_holder(const std::string& lease_id) const;
  // A worker that still holds a live lease gets that lease back (reconnect); otherwise a
  // new lease on up to `max_tiles` of the best pending tiles: highest priority job first,
  // then oldest job, tiles centre-first. The batch is cut to the worker's share of the
  // job's pending tiles, so that the last tiles of a job spread over every worker.
  Pending<std::optional<LeaseRecord>> claim(const std::string& worker_id, int max_tiles = 1);
  // Extends the lease; nothing when it is no longer live.
  Pending<std::optional<LeaseRecord>> heartbeat(const std::string& lease_id);
  // More tiles for a live lease, so that its worker renders on without the round trips of
  // a claim between batches: up to `max_tiles` more of the lease's job, cut as claim()
  // cuts a batch, while that job is the one claim() would give this worker. Renews the
  // lease as heartbeat() does. The LeaseRecord returned lists only the tiles added, which may
  // be none; nothing when the lease is no longer live.
  Pending<std::optional<LeaseRecord>> extend(const std::string& lease_id, int max_tiles);
  // Stores the results of some or all of the lease's tiles, atomically: every tile is
  // accepted or none is. The pixels must stay valid until when_stored() has answered: the
  // store thread writes them, and pastes them into the job's canvas once they are durable.
  // A refusal by the store makes the answer ResultOutcome::unstored.
  Pending<ResultOutcome> complete(const std::string& lease_id, std::span<const TileResult> results);
  // The pixels of every tile the lease still owes, concatenated in the lease's order; the
  // rays are counted once, on the first of them.
  Pending<ResultOutcome> complete(const std::string& lease_id, std::span<const float> pixels,
                                  std::uint64_t rays);
  // The pixel count of each of the lease's job's tiles named by index (0 for an index the
  // job does not have), to cut an upload into tiles; nothing when the lease is unknown.
  std::optional<std::vector<std::size_t>> tile_pixel_counts(
      const std::string& lease_id, std::span<const std::uint64_t> tile_indexes) const;
  // The worker gives its remaining tiles back (for example on SIGTERM) without results.
  Written release(const std::string& lease_id);
  // The worker could not render `tile_index`: that tile fails once (see max_tile_attempts)
  // and the lease's other tiles go back as by release(). Nothing when the lease is not
  // live or does not owe that tile.
  Written fail_tile(const std::string& lease_id, int tile_index, const std::string& error);
  // The coordinator refused a result under this lease for a reason other than a lost lease
  // (over a limit, malformed): a bug or a version mismatch, shown on the lease's job.
  void note_refused_result(const std::string& lease_id, const std::string& why);
  // Records that a worker is alive (any request from it).
  Written touch_worker(const std::string& worker_id);
  Written worker_left(const std::string& worker_id);
  std::vector<WorkerRecord> workers() const;
  // For GET /metrics (scheduler_controls.cpp).
  const FarmCounters& counters() const { return counters_; }
  FarmGauges gauges() const;
  // A draining worker keeps its lease until it is done (or runs out) and then gets no
  // more tiles, until it is drained no longer (`draining` false).
  Pending<ControlOutcome> drain_worker(const std::string& worker_id, bool draining);
  // The worker leaves the list and the store; the tiles it owed go back to the queue. A
  // worker process still running registers again at its next call, as a new worker.
  Pending<ControlOutcome> remove_worker(const std::string& worker_id);

  // --- time -----------------------------------------------------------------
  // Returns expired leases' tiles to the queue, and fails jobs stalled past
  // stall_timeout_ms. Call periodically.
  Written expire_leases();
  // Called (outside the lock) whenever a tile may have become claimable.
  void on_work_available(std::function<void()> callback);
  // Called whenever a job has finished (completed, failed or canceled), once that is
  // durable, on the store thread: it is meant to post a wake-up elsewhere.
  void on_job_finished(std::function<void()> callback);
  // Tells `observer` of every change from now on (null: nobody); set before serving.
  void observe(FarmObserver* observer);
  // Every tile of the job as the observer tells them (without pixels), in index order;
  // nothing when there is no such job.
  std::optional<std::vector<FarmObserver::TileChange>> tiles(const std::string& job_id) const;
  // At most `limit` of them from index `offset` on, and how many the job has: a page of
  // bounded memory, whatever the job's size.
  std::optional<std::vector<FarmObserver::TileChange>> tiles(const std::string& job_id,
                                                             std::size_t offset, std::size_t limit,
                                                             std::size_t& total) const;
  // Why a new job of `tiles` tiles does not fit config().job_memory_budget beside the jobs
  // held now (their tiles reckoned at kTileBytes each); nothing when it fits.
  std::optional<std::string> job_memory_refusal(std::uint64_t tiles) const;
  // The jobs' tiles as reckoned for the budget, in bytes.
  std::uint64_t job_memory() const { return job_memory_.load(); }
  // Before what the callbacks use goes away (the server's long polls): drops them, then
  // waits for the work still in flight to be done.
  void stop_notifying();

 private:
  // The tiles bound to one lease id: live (still owed) and delivered (pixels stored).
  struct LeaseTiles {
    std::string job_id;
    std::vector<int> live;  // in no particular order; at most max_lease_tiles
    // A count, not a list: a lease that is extended for a whole job delivers all its tiles,
    // and whether a tile came under this lease is its own result_lease_id.
    int delivered = 0;
    // When the live tiles expire; they all share one expiry (claim(), heartbeat() and
    // load_and_reconcile() set it for every live tile at once). Indexed in expiries_.
    std::int64_t expires_ms = 0;
  };
  using Callbacks = std::vector<std::function<void()>>;

  // Everything below runs with mutex_ held.
  void load_and_reconcile();
  // The steps of load_and_reconcile() (scheduler_load.cpp), in its order.
  void load_workers(std::vector<WorkerRow>& rows);
  // Returns the jobs whose stored state this build does not know.
  std::set<std::string> load_jobs(std::vector<JobRow>& rows);
  // A tile named by a stored row; nothing for a job or an index that does not exist.
  TileSlot* stored_tile(const std::string& job_id, int index);
  // Marks the tiles of usable results done; stages the others' forgetting.
  void load_results(const std::vector<ResultRow>& rows, StagedChange& change);
  void recount_health(std::int64_t now);
  // Keeps each worker's one live lease, with a fresh timeout, and sends the others' tiles
  // back to the queue; a worker without a lease is gone until it talks again.
  void stage_leases_kept(StagedChange& change, std::int64_t now);
  // Brings each job's state in line with its tiles and frames.
  void stage_job_states(StagedChange& change, std::int64_t now);
  JobEntry* find_job(const std::string& id) const;
  WorkerEntry* find_worker(const std::string& id) const;
  // The worker's id as tiles hold it: one text for all the tiles it holds or rendered.
  SharedText worker_text(const std::string& id) const;
  // The image thread could not write a completed job's image: the job fails.
  void image_write_failed(const std::string& id, const std::string& error);

  // The one way state changes: apply `change` to memory and queue its write, recorded from
  // memory as it was before. Should the store refuse it, the change's jobs fail with "cannot
  // store `what`". Returns the write's ticket.
  StoreTicket commit(StagedChange& change, const std::string& what = "a change");
  StoreThread::Work record(const StagedChange& change) const;
  void apply(StagedChange& change);
  // Queues a write for the store thread; the one place that does.
  StoreTicket queue_write(StoreThread::Work work);
  // `value` as the answer of an operation that began when last_write_ was `before`.
  template <class T>
  Pending<T> pending(T value, StoreTicket before) const {
    return {std::move(value), last_write_, last_write_ > before};
  }
  // A tile a change delivered: the job, the tile, the lease it came from.
  struct Delivery {
    std::string job_id;
    int tile = 0;
    std::string lease_id;
  };
  // The store refused a change (a full disk, say): the job fails with `error`, in the
  // store if it still takes that much, in memory at least, and those of `undelivered`
  // that are its tiles are pending again, as the store has them: a retry renders them
  // again rather than completing without their pixels. A restart, with room again,
  // resumes the job from what was stored.
  void fail_unstorable(JobEntry& job, const std::string& error,
                       const std::vector<Delivery>& undelivered);
  void apply_job(JobEntry& job, const JobRecord& next);
  void apply_tile(JobEntry& job, int index, TileSlot next);
  // Adds (+1) or removes (-1) a tile's share of the indexes: pending set, counters and
  // leases_.
  void track_tile(JobEntry& job, int index, int sign);
  // Adds (+1) or removes (-1) one tile from a lease's `live` list, or (`live` false) from
  // its delivered count; a live tile also moves the lease in expiries_ to `expires_ms`.
  void index_lease_tile(const std::string& lease_id, const std::string& job_id, int index, int sign,
                        bool live, std::int64_t expires_ms = 0);
  // Moves a live lease's expiry, in memory only: the store's copy is never read back as
  // such, since a restart gives every lease a fresh timeout (load_and_reconcile()), and
  // writing every tile of every lease at every heartbeat and extension cost the coordinator
  // more than the rest of an extension at small tile sizes.
  void renew_lease(const std::string& lease_id, std::int64_t expires_ms);
  // Takes the tile order of a freshly built job (computes it when `order` is empty) and
  // tracks all its tiles.
  void index_tiles(JobEntry& job, std::vector<int> order = {});
  // A frame's tiles are pending (handed out) only while it has not failed: when one of its
  // tiles spends its attempts the others leave the pending set, and come back should the
  // job be retried.
  void set_frame_pending(JobEntry& job, int slot, bool pending);
  FrameRecord frame_info(const JobEntry& job, int slot) const;
  // The first frame of the job `id` (a still's 0); nothing when there is no such job.
  std::optional<int> first_frame(const std::string& id) const;
  // The slot of the scene's frame `frame` in the job; nothing when it does not render it.
  static std::optional<int> slot_of_frame(const JobEntry& job, int frame);
  // Why a job of failed frames failed: the frames failed so far and `more` (staged now),
  // and the first one's error.
  std::string failed_frames_error(const JobEntry& job, const std::vector<int>& more,
                                  const StagedChange& change) const;

  // Stages taking the lease off its live tiles and its worker. An expired lease counts a
  // failure against each tile it still owed.
  void stage_lease_end(StagedChange& change, const std::string& lease_id, bool expired);
  // Stages one failure of a tile by a worker; at the limit, the job fails with `error`.
  void stage_tile_failure(StagedChange& change, JobEntry& job, int index, const WorkerEntry* worker,
                          const std::string& error);
  // Counts one more hand-out of a tile, staged (claim(), extend()) or in place (a lease
  // given back on a reconnect); a tile that goes out again is shown on its job.
  void count_handout(JobEntry& job, TileSlot& tile);
  // The results an upload under `lease_id` delivers for the first time (naming each tile
  // in `named`), or the outcome that refuses the whole upload (scheduler_results.cpp).
  std::variant<ResultOutcome, std::vector<const TileResult*>> fresh_results(
      const JobEntry& job, const std::string& lease_id, const std::vector<int>& live,
      std::span<const TileResult> results, std::set<int>& named) const;
  // Stages the fresh results' tiles as done, with the job's rays and the worker's next
  // tile, and the job's end when they settle its last open frame; true when they are
  // their frame's last.
  bool stage_results(StagedChange& change, JobEntry& job, const std::string& lease_id,
                     const std::vector<const TileResult*>& fresh, const std::vector<int>& live,
                     const std::set<int>& named);
  // Stages the job's failure with `error`, withdrawing its other tiles from their workers;
  // nothing when it has finished already.
  void stage_job_failure(StagedChange& change, JobEntry& job, const std::string& error);
  // Fails the running jobs that delivered nothing for stall_timeout_ms while rendering.
  void fail_stalled_locked(std::int64_t now, StagedChange& change);
  // Whether `worker` should get none of `job`'s tiles, having failed on it too often.
  bool kept_off(const JobEntry& job, const WorkerEntry& worker) const;
  // Returns the tiles of leases expired at `now` to the queue; true when there were any.
  bool expire_locked(std::int64_t now);
  // Drops the workers gone or left longer than config_.forget_workers_after_ms.
  void forget_workers_locked(std::int64_t now);
  LeaseRecord lease_of(const std::string& lease_id) const;
  std::string new_lease_id() const;
  // The job a claim by `worker` takes tiles of: the first in claim order with a pending
  // tile it is not kept off; none when there is none.
  JobEntry* next_job_for(const WorkerEntry& worker) const;
  // How many tiles a claim for up to `max_tiles` of `job` gets.
  int batch_size(const JobEntry& job, int max_tiles) const;
  // Stages up to `count` of the job's pending tiles, in hand-out order, onto the lease;
  // returns their indexes in that order. An extension (`extending`) stops before a tile
  // that failed before, which goes out alone under a lease of its own. A lease's tiles are
  // of one frame: the batch stops at the end of its first tile's frame, or takes nothing
  // but tiles of frame slot `slot` when that is not -1 (an extension's lease's).
  std::vector<int> stage_batch(StagedChange& change, JobEntry& job, const std::string& lease_id,
                               const std::string& worker_id, int count, std::int64_t expires_ms,
                               bool extending, int slot = -1);
  // Records contact; persisted at most once per second per worker.
  void note_seen(WorkerEntry& worker, std::int64_t now);

  Store& store_;
  const Clock& clock_;
  SchedulerConfig config_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, std::unique_ptr<JobEntry>> jobs_;
  // Jobs that may hand out tiles, in claim order: (-priority, created_at, id).
  std::set<std::tuple<int, std::int64_t, std::string>> active_;
  // Every lease id that binds a tile, live or delivered. A lease is live while `live` is
  // not empty.
  std::unordered_map<std::string, LeaseTiles> leases_;
  // The live leases by expiry, soonest first, so that a claim finds the expired ones
  // without looking at every lease (leases_ keeps every lease that delivered a tile).
  std::set<std::pair<std::int64_t, std::string>> expiries_;
  // Workers that have not left ("gone"), for batch_size() on every claim.
  int present_workers_ = 0;
  std::unordered_map<std::string, std::unique_ptr<WorkerEntry>> workers_;
  // Worker ids by the digest of their secret (workers of a store from before secrets have
  // none, and cannot prove themselves: they register again).
  std::unordered_map<std::string, std::string> secret_owners_;
  Callbacks callbacks_;
  Callbacks finished_callbacks_;
  FarmCounters counters_;
  FarmObserver* observer_ = nullptr;
  // The records a staged change touches, taken before it is applied (scheduler_observe.cpp),
  // and then told to the observer as they are after it, once it is durable.
  struct Observed {
    std::vector<JobEntry*> jobs;
    std::vector<std::pair<JobEntry*, int>> tiles;
    std::vector<std::pair<WorkerEntry*, protocol::WorkerState>> workers;  // with the state before
  };
  Observed observed_before(const StagedChange& change) const;
  // A farm control of the job `id` (scheduler_controls.cpp): `change_job(job, change)`
  // stages what it changes, or returns why it refuses; what it stages is committed, and
  // `durable`, where given, runs on the store thread once it is durable.
  template <typename Change>
  Pending<ControlOutcome> control_job(const std::string& id, Change change_job,
                                      std::function<void()> durable = {});
  void tell_observer(const Observed& observed, StoreTicket ticket);
  FarmObserver::TileChange tile_change(const JobEntry& job, int index) const;
  StoreTicket last_write_ = 0;              // the ticket of the last write queued by queue_write()
  std::atomic<std::uint64_t> refusals_{0};  // see refusals()
  std::atomic<std::uint64_t> job_memory_{0};  // see job_memory(); changed under the lock
  // During start-up: the unfinished jobs left without tiles by the budget, and why.
  std::map<std::string, std::string> not_loaded_;
  // After what its callbacks use, so that it finishes them first when destroyed.
  mutable StoreThread store_thread_;
  // After the store thread, which its image thread uses until it has stopped.
  ImageAssembly images_;
};

}  // namespace tessera
