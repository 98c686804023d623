// The coordinator's store: one SQLite database (WAL) and the tiles' pixel files, both under
// one data directory, beside the finished images.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "server/farm/sqlite_db.hpp"
#include "server/farm/store.hpp"

namespace tessera {

class SqliteStore final : public Store {
 public:
  // Creates the directory and the database when they do not exist yet.
  explicit SqliteStore(const std::filesystem::path& data_dir);

  const std::filesystem::path& data_dir() const override { return data_dir_; }
  // data_dir/pixels/<job_id>.f32: the pixels of the job's results, each appended as it
  // is accepted, float32 RGB little-endian, tile after tile. Append-only, so that a backup
  // of the database taken before a copy of these files finds every pixel it points to.
  std::filesystem::path pixel_path(const std::string& job_id) const;
  // The same within the data dir ("pixels/JOB.f32"): how errors that reach clients name it.
  static std::string pixel_name(const std::string& job_id);

  StoredState load() override;
  // One SQLite transaction; nested in another, a savepoint.
  void atomically(const std::function<void()>& writes) override;

  void insert_job(const JobRow& job, const std::string& scene_json) override;
  void update_job(const JobRow& job) override;
  // Also deletes its pixel file, after the commit.
  void delete_job(const std::string& job_id) override;
  std::optional<std::string> scene_json(const std::string& digest) override;

  void put_lease(const LeaseRow& lease) override;
  void delete_lease(const std::string& lease_id) override;
  // Appends the pixels to the job's pixel file, then inserts the row that points to them
  // (in the caller's transaction, if any; a rollback leaves bytes in the file that nothing
  // points to).
  std::int64_t insert_result(const ResultRow& result,
                             std::span<const std::span<const float>> pixels) override;
  void delete_result(std::int64_t result_id) override;
  void put_tile_failure(const TileFailureRow& failure) override;
  void for_each_tile_pixels(
      const std::string& job_id, const std::function<std::size_t(int tile_index)>& floats_of,
      const std::function<void(int tile_index, std::span<const float>)>& visit,
      const std::function<bool(int tile_index)>& wanted = {}) override;

  void upsert_worker(const WorkerRow& worker) override;
  void delete_worker(const std::string& id) override;
  void update_worker_seen(const std::string& worker_id, std::int64_t last_seen_ms) override;

  // Deletes pixel files whose job is not kept.
  void prune_pixels(const std::function<bool(const std::string& job_id)>& keep) override;

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
