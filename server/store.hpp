// The coordinator's durable state: one SQLite database (WAL) and the finished images,
// both under one data directory. Rows mirror the Scheduler's records; states are stored
// as the words the Scheduler uses, so that the database reads well with the sqlite3 tool.
// Not thread-safe: the Scheduler calls it under its lock.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/image.hpp"
#include "server/sqlite_db.hpp"

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
};

struct TileRow {
  std::string job_id;
  int tile_index = 0;
  TileRect rect;
  std::string state;
  std::string lease_id;   // the live lease; "" when none
  std::string worker_id;  // the lease holder, or who rendered a done tile
  std::int64_t lease_expires_ms = 0;
  int attempts = 0;  // times it failed: its lease expired, or its worker reported an error
  std::uint64_t rays = 0;
  std::string result_lease_id;   // the lease whose pixels are stored; "" when none
  std::string last_error;        // why it failed last; "" when it never did
  std::int64_t pixel_bytes = 0;  // size of the stored pixels; read by load() only
};

struct WorkerRow {
  std::string id;
  std::string name;
  std::string host;
  int threads = 0;
  std::string state;
  std::uint64_t tiles_rendered = 0;
  std::int64_t last_seen_ms = 0;
};

struct StoredState {
  std::vector<JobRow> jobs;
  std::vector<TileRow> tiles;  // by job, then tile index; without pixels
  std::vector<WorkerRow> workers;
};

class Store {
 public:
  // Creates the directory and the database when they do not exist yet.
  explicit Store(const std::filesystem::path& data_dir);

  const std::filesystem::path& data_dir() const { return data_dir_; }
  std::filesystem::path image_path(const std::string& job_id) const;

  // Everything but pixels and scene texts, for the Scheduler to start from.
  StoredState load();

  // Groups several operations into one atomic change.
  Transaction transaction() { return Transaction(db_); }

  // The job, its tiles and (unless already stored under the digest) its scene, atomically.
  // Tiles are stored in the order given: the Scheduler gives them in hand-out order, so
  // that the rows a lease changes together lie together.
  void insert_job(const JobRow& job, const std::string& scene_json, std::span<const TileRow> tiles);
  // The same, with the tiles made one at a time by `tile_at` (i from 0 to tile_count - 1).
  void insert_job(const JobRow& job, const std::string& scene_json, std::size_t tile_count,
                  const std::function<void(std::size_t i, TileRow& row)>& tile_at);
  void update_job(const JobRow& job);
  // Deletes the job, its tiles, its scene when no other job uses it, and its image.
  void delete_job(const std::string& job_id);
  std::optional<std::string> scene_json(const std::string& digest);

  // Everything but the pixels.
  void update_tile(const TileRow& tile);
  // The tile's new state together with its pixels (RGB float32, row-major), atomically.
  void store_tile_result(const TileRow& tile, std::span<const float> pixels);
  // The same, inside a transaction the caller holds (`open` says there is one), which
  // keeps it atomic: a savepoint of its own per tile would double the statements of every
  // upload, which the coordinator pays per tile.
  void store_tile_result(const Transaction& open, const TileRow& tile, std::span<const float> pixels);
  // Calls `visit` for each tile of the job that has pixels; the span is valid during the call.
  void for_each_tile_pixels(
      const std::string& job_id,
      const std::function<void(int tile_index, std::span<const float>)>& visit);

  void upsert_worker(const WorkerRow& worker);
  void update_worker_seen(const std::string& worker_id, std::int64_t last_seen_ms);

  // Writes data_dir/images/<job_id>.exr (linear, atomically replaced). Touches no database
  // state, so it may run beside the other calls.
  void write_image(const std::string& job_id, const Image& image);
  void remove_image(const std::string& job_id);
  bool has_image(const std::string& job_id) const;
  // Deletes image files (and leftovers of interrupted writes) whose job is not kept.
  void prune_images(const std::function<bool(const std::string& job_id)>& keep);

 private:
  void create_schema();

  std::filesystem::path data_dir_;
  SqliteDb db_;
};

}  // namespace tessera
