// A Store in memory, for the Scheduler's unit tests: a test that restarts the coordinator
// makes a new Scheduler on the same MemoryStore, which keeps what was committed, as a disk
// would. It checks what SQLite's constraints check (a lease, result or failure of a job
// that does not exist is refused), and it can be told to refuse writes, as a full disk does.
// Unlike SqliteStore it may be called from any thread, so that a test can look at what is
// stored while the store thread writes: a change is seen whole or not at all.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "server/farm/store.hpp"
#include "server/farm/store_error.hpp"

namespace tessera {

class MemoryStore final : public Store {
 public:
  // `data_dir`: where the coordinator writes its images; the store writes nothing there.
  explicit MemoryStore(std::filesystem::path data_dir);

  const std::filesystem::path& data_dir() const override { return data_dir_; }
  StoredState load() override;
  void atomically(const std::function<void()>& writes) override;

  void insert_job(const JobRow& job, const std::string& scene_json) override;
  void update_job(const JobRow& job) override;
  void delete_job(const std::string& job_id) override;
  std::optional<std::string> scene_json(const std::string& digest) override;
  void put_lease(const LeaseRow& lease) override;
  void delete_lease(const std::string& lease_id) override;
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
  void prune_pixels(const std::function<bool(const std::string& job_id)>& keep) override;

  // From now on every write throws StoreError(`fault`, `why`), until refuse_writes() with
  // nothing; reads go on.
  void refuse_writes(std::optional<std::string> why, StoreFault fault = StoreFault::disk_full);
  // The atomically() calls that committed so far.
  std::uint64_t commits() const;

 private:
  struct StoredResult {
    ResultRow row;
    std::vector<float> pixels;  // every tile's, in the order of row.tiles
  };
  using FailureKey = std::pair<std::string, int>;  // job, tile

  // Throws when writes are refused.
  void check_writable() const;
  void check_job(const std::string& job_id, const char* what) const;
  // Within atomically(): remembers `key`'s entry in `map` as it is now, to restore should
  // the change throw.
  template <class Map>
  void keep_undo(Map& map, const typename Map::key_type& key);
  template <class Map>
  void erase_kept(Map& map, typename Map::key_type key) {  // a copy: the entry goes
    keep_undo(map, key);
    map.erase(key);
  }

  std::filesystem::path data_dir_;
  std::map<std::string, std::string> scenes_;  // by digest
  std::map<std::string, JobRow> jobs_;
  std::map<std::string, LeaseRow> leases_;
  std::map<std::int64_t, StoredResult> results_;  // by id: the order they were stored in
  std::map<FailureKey, TileFailureRow> failures_;
  std::map<std::string, WorkerRow> workers_;
  std::int64_t next_result_id_ = 1;
  // Held by every call, and through a whole atomically(): recursive, since that calls the
  // others.
  mutable std::recursive_mutex mutex_;
  std::optional<std::string> refusal_;
  StoreFault refusal_fault_ = StoreFault::disk_full;
  std::uint64_t commits_ = 0;
  // While atomically() runs: how to undo each write so far, in order.
  bool in_change_ = false;
  std::vector<std::function<void()>> undo_;
};

}  // namespace tessera
