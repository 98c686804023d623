#include "server/farm/memory_store.hpp"

#include <algorithm>
#include <stdexcept>

namespace tessera {

MemoryStore::MemoryStore(std::filesystem::path data_dir) : data_dir_(std::move(data_dir)) {}

StoredState MemoryStore::load() {
  std::lock_guard lock(mutex_);
  StoredState state;
  for (const auto& [id, job] : jobs_) state.jobs.push_back(job);
  for (const auto& [id, lease] : leases_) state.leases.push_back(lease);
  for (const auto& [id, result] : results_) {
    ResultRow& row = state.results.emplace_back(result.row);
    row.pixel_bytes = static_cast<std::int64_t>(result.pixels.size() * sizeof(float));
  }
  for (const auto& [key, failure] : failures_) state.failures.push_back(failure);
  for (const auto& [id, worker] : workers_) state.workers.push_back(worker);
  return state;
}

void MemoryStore::atomically(const std::function<void()>& writes) {
  std::lock_guard lock(mutex_);
  if (in_change_) return writes();  // a part of the change already under way
  in_change_ = true;
  try {
    writes();
  } catch (...) {
    for (auto undo = undo_.rbegin(); undo != undo_.rend(); ++undo) (*undo)();
    undo_.clear();
    in_change_ = false;
    throw;
  }
  undo_.clear();
  in_change_ = false;
  ++commits_;
}

template <class Map>
void MemoryStore::keep_undo(Map& map, const typename Map::key_type& key) {
  if (!in_change_) return;
  const auto it = map.find(key);
  if (it == map.end())
    undo_.push_back([&map, key] { map.erase(key); });
  else
    undo_.push_back([&map, key, was = it->second] { map.insert_or_assign(key, was); });
}

void MemoryStore::check_writable() const {
  if (refusal_) throw StoreError(refusal_fault_, *refusal_);
}

void MemoryStore::check_job(const std::string& job_id, const char* what) const {
  // As SQLite's foreign keys refuse it.
  if (!jobs_.contains(job_id))
    throw StoreError(StoreFault::other,
                     std::string("store: ") + what + " of job " + job_id + ", which is not stored");
}

void MemoryStore::insert_job(const JobRow& job, const std::string& scene_json) {
  std::lock_guard lock(mutex_);
  check_writable();
  if (jobs_.contains(job.id))
    throw StoreError(StoreFault::other, "store: job " + job.id + " is stored already");
  if (!scenes_.contains(job.scene_digest)) {
    keep_undo(scenes_, job.scene_digest);
    scenes_.emplace(job.scene_digest, scene_json);
  }
  keep_undo(jobs_, job.id);
  jobs_.emplace(job.id, job);
}

void MemoryStore::update_job(const JobRow& job) {
  std::lock_guard lock(mutex_);
  check_writable();
  const auto it = jobs_.find(job.id);
  if (it == jobs_.end()) return;  // as an UPDATE that matches no row
  keep_undo(jobs_, job.id);
  JobRow& stored = it->second;
  stored.name = job.name;
  stored.priority = job.priority;
  stored.state = job.state;
  stored.started_at_ms = job.started_at_ms;
  stored.finished_at_ms = job.finished_at_ms;
  stored.error = job.error;
  stored.rays = job.rays;
}

void MemoryStore::delete_job(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  check_writable();
  const auto job = jobs_.find(job_id);
  if (job == jobs_.end()) return;
  const std::string digest = job->second.scene_digest;
  erase_kept(jobs_, job_id);
  for (auto it = leases_.begin(); it != leases_.end();) {
    const auto next = std::next(it);
    if (it->second.job_id == job_id) erase_kept(leases_, it->first);
    it = next;
  }
  for (auto it = results_.begin(); it != results_.end();) {
    const auto next = std::next(it);
    if (it->second.row.job_id == job_id) erase_kept(results_, it->first);
    it = next;
  }
  for (auto it = failures_.lower_bound({job_id, 0});
       it != failures_.end() && it->first.first == job_id;) {
    const auto next = std::next(it);
    erase_kept(failures_, it->first);
    it = next;
  }
  const bool shared = std::any_of(jobs_.begin(), jobs_.end(), [&](const auto& entry) {
    return entry.second.scene_digest == digest;
  });
  if (!shared) erase_kept(scenes_, digest);
}

std::optional<std::string> MemoryStore::scene_json(const std::string& digest) {
  std::lock_guard lock(mutex_);
  const auto it = scenes_.find(digest);
  if (it == scenes_.end()) return std::nullopt;
  return it->second;
}

void MemoryStore::put_lease(const LeaseRow& lease) {
  std::lock_guard lock(mutex_);
  check_writable();
  check_job(lease.job_id, "a lease");
  keep_undo(leases_, lease.id);
  const auto [it, inserted] = leases_.try_emplace(lease.id, lease);
  if (inserted) return;
  // As the SQLite store's upsert: the job a lease is of never changes.
  it->second.worker_id = lease.worker_id;
  it->second.tiles = lease.tiles;
}

void MemoryStore::delete_lease(const std::string& lease_id) {
  std::lock_guard lock(mutex_);
  check_writable();
  erase_kept(leases_, lease_id);
}

std::int64_t MemoryStore::insert_result(const ResultRow& result,
                                        std::span<const std::span<const float>> pixels) {
  std::lock_guard lock(mutex_);
  check_writable();
  check_job(result.job_id, "a result");
  StoredResult stored{result, {}};
  for (const std::span<const float> tile : pixels)
    stored.pixels.insert(stored.pixels.end(), tile.begin(), tile.end());
  const std::int64_t id = next_result_id_++;
  stored.row.id = id;
  stored.row.pixel_bytes = 0;
  keep_undo(results_, id);
  results_.emplace(id, std::move(stored));
  return id;
}

void MemoryStore::delete_result(std::int64_t result_id) {
  std::lock_guard lock(mutex_);
  check_writable();
  erase_kept(results_, result_id);
}

void MemoryStore::put_tile_failure(const TileFailureRow& failure) {
  std::lock_guard lock(mutex_);
  check_writable();
  check_job(failure.job_id, "a tile failure");
  const FailureKey key{failure.job_id, failure.tile_index};
  keep_undo(failures_, key);
  failures_.insert_or_assign(key, failure);
}

void MemoryStore::for_each_tile_pixels(
    const std::string& job_id, const std::function<std::size_t(int tile_index)>& floats_of,
    const std::function<void(int tile_index, std::span<const float>)>& visit,
    const std::function<bool(int tile_index)>& wanted) {
  std::lock_guard lock(mutex_);
  for (const auto& [id, result] : results_) {
    if (result.row.job_id != job_id) continue;
    const std::vector<int>& tiles = result.row.tiles;
    if (wanted && std::none_of(tiles.begin(), tiles.end(), wanted)) continue;
    std::size_t offset = 0;
    for (const int index : tiles) {
      const std::size_t size = floats_of(index);
      if (offset + size > result.pixels.size())
        throw std::runtime_error("store: the stored pixels of job " + job_id + " end before tile " +
                                 std::to_string(index));
      if (!wanted || wanted(index))
        visit(index, std::span<const float>(result.pixels).subspan(offset, size));
      offset += size;
    }
  }
}

void MemoryStore::upsert_worker(const WorkerRow& worker) {
  std::lock_guard lock(mutex_);
  check_writable();
  keep_undo(workers_, worker.id);
  workers_.insert_or_assign(worker.id, worker);
}

void MemoryStore::delete_worker(const std::string& id) {
  std::lock_guard lock(mutex_);
  check_writable();
  erase_kept(workers_, id);
}

void MemoryStore::update_worker_seen(const std::string& worker_id, std::int64_t last_seen_ms) {
  std::lock_guard lock(mutex_);
  check_writable();
  const auto it = workers_.find(worker_id);
  if (it == workers_.end()) return;
  keep_undo(workers_, worker_id);
  it->second.last_seen_ms = last_seen_ms;
}

void MemoryStore::prune_pixels(const std::function<bool(const std::string& job_id)>&) {
  // A job's pixels go with its results, which delete_job() removes: none are left over.
}

std::uint64_t MemoryStore::commits() const {
  std::lock_guard lock(mutex_);
  return commits_;
}

void MemoryStore::refuse_writes(std::optional<std::string> why, StoreFault fault) {
  std::lock_guard lock(mutex_);
  refusal_ = std::move(why);
  refusal_fault_ = fault;
}

}  // namespace tessera
