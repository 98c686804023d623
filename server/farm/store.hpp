// The coordinator's durable state: one SQLite database (WAL) and the finished images,
// both under one data directory. Rows mirror the Scheduler's records; states are stored
// as the words the Scheduler uses, so that the database reads well with the sqlite3 tool.
// Not thread-safe: once the coordinator serves, only its store thread (StoreThread) calls it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/image/image.hpp"
#include "server/farm/sqlite_db.hpp"

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

class Store {
 public:
  // Creates the directory and the database when they do not exist yet.
  explicit Store(const std::filesystem::path& data_dir);

  const std::filesystem::path& data_dir() const { return data_dir_; }
  // data_dir/pixels/<job_id>.f32: the pixels of the job's results, each appended as it
  // is accepted, float32 RGB little-endian, tile after tile. Append-only, so that a backup
  // of the database taken before a copy of these files finds every pixel it points to.
  std::filesystem::path pixel_path(const std::string& job_id) const;
  // The same within the data dir ("pixels/JOB.f32"): how errors that reach clients name it.
  static std::string pixel_name(const std::string& job_id);

  // Everything but pixels and scene texts, for the Scheduler to start from.
  StoredState load();

  // Groups several operations into one atomic change.
  Transaction transaction() { return Transaction(db_); }

  // The job and (unless already stored under the digest) its scene, atomically. Its tiles
  // follow from its size and tile size; they have no rows until something happens to them.
  void insert_job(const JobRow& job, const std::string& scene_json);
  void update_job(const JobRow& job);
  // Deletes the job, its leases, results and failures, its scene when no other job uses
  // it, and its pixel file (not its image: ImageFiles keeps those).
  void delete_job(const std::string& job_id);
  std::optional<std::string> scene_json(const std::string& digest);

  // Stores the lease with the tiles it now owes, replacing what was stored of it.
  void put_lease(const LeaseRow& lease);
  void delete_lease(const std::string& lease_id);
  // Stores an accepted upload, `pixels` holding one span per tile of `result.tiles`:
  // appends them to the job's pixel file, then inserts the row that points to them (in the
  // caller's transaction, if any; a rollback leaves bytes in the file that nothing points
  // to). Returns the result's id.
  std::int64_t insert_result(const ResultRow& result,
                             std::span<const std::span<const float>> pixels);
  // Forgets a result whose pixels cannot be used (load() found them cut short).
  void delete_result(std::int64_t result_id);
  // Stores how often the tile failed and why, replacing what was stored of it.
  void put_tile_failure(const TileFailureRow& failure);
  // Calls `visit` for each tile of the job's results, in the order they were stored;
  // `floats_of(tile_index)` says how many floats each tile has (load() has checked that
  // they add up). The span is valid during the call. With `wanted`, a result none of whose
  // tiles it wants is not read at all: one frame of an animation is read without the
  // pixels of the others.
  void for_each_tile_pixels(
      const std::string& job_id, const std::function<std::size_t(int tile_index)>& floats_of,
      const std::function<void(int tile_index, std::span<const float>)>& visit,
      const std::function<bool(int tile_index)>& wanted = {});

  void upsert_worker(const WorkerRow& worker);
  void delete_worker(const std::string& id);
  void update_worker_seen(const std::string& worker_id, std::int64_t last_seen_ms);

  // Deletes pixel files whose job is not kept (left by a removal that stopped half-way).
  void prune_pixels(const std::function<bool(const std::string& job_id)>& keep);

 private:
  // The tables of load(), each read in load()'s transaction.
  std::vector<JobRow> job_rows();
  std::vector<LeaseRow> lease_rows();
  // With each result's pixel_bytes cut to what its job's pixel file holds.
  std::vector<ResultRow> result_rows();
  std::vector<TileFailureRow> failure_rows();
  std::vector<WorkerRow> worker_rows();
  void create_schema();
  // Version 3 kept a row per tile; version 4 keeps leases, results and failures.
  void migrate_tile_rows();
  // Appends the parts to the job's pixel file; returns where the first starts.
  std::int64_t append_pixels(const std::string& job_id,
                             std::span<const std::span<const std::byte>> parts);
  std::int64_t insert_result_at(const ResultRow& result, std::int64_t pixels_at,
                                std::size_t pixel_bytes);

  std::filesystem::path data_dir_;
  SqliteDb db_;
};

}  // namespace tessera
