// The coordinator's durable state, as rows, and Store, the seam between the Scheduler and
// what keeps them. Rows mirror the Scheduler's records; states are stored as the protocol's
// words, so that a database reads well with its own tools.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/image/image.hpp"

namespace tessera {

struct JobRow {
  std::string id;
  std::string name;
  int priority = 0;
  std::string state;
  int width = 0;
  int height = 0;
  int tile_size = 0;
  std::string scene_digest;
  std::int64_t created_at_ms = 0;
  std::int64_t started_at_ms = 0;
  std::int64_t finished_at_ms = 0;
  std::string error;
  std::uint64_t rays = 0;
  // Facts of the scene that later requests need, kept at submit so that no request parses
  // the scene again: how its 8- and 16-bit images are encoded ("srgb" or "linear").
  std::string output_transfer = "srgb";
  // The frames of an animation it renders, as a frame list ("1-48", in the order they go
  // out); "" for a still, its one frame 0. Its tiles are every frame's, one frame after
  // the other.
  std::string frames;
};

// A live lease: the tiles it still owes. Its expiry is not stored: a restart gives every
// lease a fresh timeout, since no heartbeat could reach a coordinator that was down.
struct LeaseRow {
  std::string id;
  std::string job_id;
  std::string worker_id;
  std::vector<int> tiles;  // in no particular order
};

// One accepted upload: the tiles it delivered and the rays each took. Its pixels lie in
// the job's pixel file (RGB float32, row-major, each tile's after the one before, in the
// order of `tiles`).
struct ResultRow {
  std::int64_t id = 0;  // given by the store
  std::string job_id;
  std::string lease_id;
  std::string worker_id;  // who rendered them
  std::vector<int> tiles;
  std::vector<std::uint64_t> rays;  // one per tile
  // The bytes of its pixels that the job's pixel file holds; read by load() only.
  std::int64_t pixel_bytes = 0;
};

// A tile that failed: how often, and why the last time.
struct TileFailureRow {
  std::string job_id;
  int tile_index = 0;
  int attempts = 0;
  std::string last_error;
};

struct WorkerRow {
  std::string id;
  std::string name;
  std::string host;
  int threads = 0;
  std::string state;
  std::uint64_t tiles_rendered = 0;
  std::int64_t last_seen_ms = 0;
  std::string secret_sha256;  // "" for a worker of a store from before secrets
  bool draining = false;
};

// A tile is pending unless a lease owes it or a result delivered it; what the store keeps
// of tiles is only those leases, results and failures, so that the coordinator writes a
// row per lease and per upload, not one per tile (a 1080p frame of 8-pixel tiles has
// 32,400 of them).
struct StoredState {
  std::vector<JobRow> jobs;
  std::vector<LeaseRow> leases;
  std::vector<ResultRow> results;  // by id, the order they were stored in; without pixels
  std::vector<TileFailureRow> failures;
  std::vector<WorkerRow> workers;
};

// What the Scheduler needs of durable state, whatever holds it: SqliteStore on a coordinator,
// MemoryStore in unit tests. A write that throws has stored nothing of itself; within
// atomically(), nothing of the whole group. Not thread-safe: once the coordinator serves,
// only its store thread (StoreThread) calls it.
class Store {
 public:
  virtual ~Store() = default;

  // Where the coordinator keeps the files beside the store: the finished images (ImageFiles).
  virtual const std::filesystem::path& data_dir() const = 0;

  // Everything but pixels and scene texts, for the Scheduler to start from.
  virtual StoredState load() = 0;
  // Runs `writes` as one atomic change: all of what it stores is durable once this returns,
  // and none of it when this throws (it rethrows what `writes` threw, or its own error).
  virtual void atomically(const std::function<void()>& writes) = 0;

  // The job and (unless already stored under the digest) its scene, atomically. Its tiles
  // follow from its size and tile size; they have no rows until something happens to them.
  virtual void insert_job(const JobRow& job, const std::string& scene_json) = 0;
  // Its name, priority, state, times, error and rays; the rest never changes.
  virtual void update_job(const JobRow& job) = 0;
  // Deletes the job, its leases, results and failures, its scene when no other job uses
  // it, and its pixels (not its image: ImageFiles keeps those).
  virtual void delete_job(const std::string& job_id) = 0;
  virtual std::optional<std::string> scene_json(const std::string& digest) = 0;

  // Stores the lease with the tiles it now owes, replacing what was stored of it.
  virtual void put_lease(const LeaseRow& lease) = 0;
  virtual void delete_lease(const std::string& lease_id) = 0;
  // Stores an accepted upload, `pixels` holding one span per tile of `result.tiles`.
  // Returns the result's id, which grows with every result stored.
  virtual std::int64_t insert_result(const ResultRow& result,
                                     std::span<const std::span<const float>> pixels) = 0;
  // Forgets a result whose pixels cannot be used (load() found them cut short).
  virtual void delete_result(std::int64_t result_id) = 0;
  // Stores how often the tile failed and why, replacing what was stored of it.
  virtual void put_tile_failure(const TileFailureRow& failure) = 0;
  // Calls `visit` for each tile of the job's results, in the order they were stored;
  // `floats_of(tile_index)` says how many floats each tile has (load() has checked that
  // they add up). The span is valid during the call. With `wanted`, a result none of whose
  // tiles it wants is not read at all: one frame of an animation is read without the
  // pixels of the others.
  virtual void for_each_tile_pixels(
      const std::string& job_id, const std::function<std::size_t(int tile_index)>& floats_of,
      const std::function<void(int tile_index, std::span<const float>)>& visit,
      const std::function<bool(int tile_index)>& wanted = {}) = 0;

  virtual void upsert_worker(const WorkerRow& worker) = 0;
  virtual void delete_worker(const std::string& id) = 0;
  virtual void update_worker_seen(const std::string& worker_id, std::int64_t last_seen_ms) = 0;

  // Forgets pixels whose job is not kept (left by a removal that stopped half-way).
  virtual void prune_pixels(const std::function<bool(const std::string& job_id)>& keep) = 0;
};

}  // namespace tessera
