// Workers: registration, liveness and departure.
#include <algorithm>

#include <spdlog/spdlog.h>
#include "server/farm/ids.hpp"

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"

namespace tessera {
namespace {

// Heartbeats and polls arrive every few seconds from every worker; last_seen is for
// display, so the database hears about it at most this often per worker.
constexpr std::int64_t seen_write_interval_ms = 1000;

}  // namespace

Pending<WorkerRecord> Scheduler::register_worker(const std::string& name, const std::string& host,
                                                 int threads, const std::string& secret_sha256) {
  std::lock_guard lock(mutex_);
  const StoreTicket before = last_write_;
  auto worker = std::make_unique<WorkerEntry>();
  WorkerRecord& info = worker->info;
  do {
    info.id = "w-" + random_hex(12);
  } while (workers_.contains(info.id));
  worker->id_text = info.id;
  info.name = name;
  info.host = host;
  info.threads = threads;
  info.state = WorkerState::idle;
  info.last_seen_ms = clock_.now_ms();
  worker->secret_sha256 = secret_sha256;
  if (!secret_sha256.empty()) secret_owners_[secret_sha256] = info.id;
  const StoreTicket ticket =
      queue_write([row = worker_row(*worker)](Store& store) { store.upsert_worker(row); });
  if (observer_)
    store_thread_.after(ticket, [observer = observer_, info = info](const std::string& error) {
      if (error.empty()) observer->workers_changed({{info, FarmObserver::WorkerChange::joined}});
    });
  worker->persisted_seen_ms = info.last_seen_ms;
  const WorkerRecord result = info;
  workers_.emplace(result.id, std::move(worker));
  ++present_workers_;
  spdlog::info("worker {} joined: {} on {}, {} thread(s)", result.id, name, host, threads);
  return pending(result, before);
}

bool Scheduler::worker_known(const std::string& worker_id) const {
  std::lock_guard lock(mutex_);
  const WorkerEntry* worker = find_worker(worker_id);
  return worker && worker->info.state != WorkerState::left;
}

std::optional<std::string> Scheduler::worker_with_secret(const std::string& secret_sha256) const {
  std::lock_guard lock(mutex_);
  const auto owner = secret_owners_.find(secret_sha256);
  if (owner == secret_owners_.end()) return std::nullopt;
  const WorkerEntry* worker = find_worker(owner->second);
  if (!worker || worker->info.state == WorkerState::left) return std::nullopt;
  return owner->second;
}

std::optional<std::string> Scheduler::lease_holder(const std::string& lease_id) const {
  std::lock_guard lock(mutex_);
  const auto lease = leases_.find(lease_id);
  if (lease == leases_.end() || lease->second.live.empty()) return std::nullopt;
  const auto job = jobs_.find(lease->second.job_id);
  if (job == jobs_.end()) return std::nullopt;
  return job->second->tiles[lease->second.live.front()].worker_id;
}

Written Scheduler::touch_worker(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  const StoreTicket before = last_write_;
  WorkerEntry* worker = find_worker(worker_id);
  if (!worker || worker->info.state == WorkerState::left) return pending(std::monostate{}, before);
  const std::int64_t now = clock_.now_ms();
  if (worker->info.state != WorkerState::gone) {
    note_seen(*worker, now);
    return pending(std::monostate{}, before);
  }
  // Marked gone (not heard from, or the coordinator restarted) but talking again.
  StagedChange change;
  WorkerEntry& staged = change.worker(*worker);
  staged.info.state = WorkerState::idle;
  staged.info.last_seen_ms = now;
  commit(change);
  return pending(std::monostate{}, before);
}

Written Scheduler::worker_left(const std::string& worker_id) {
  Callbacks notify;
  Written answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    WorkerEntry* worker = find_worker(worker_id);
    if (!worker) return pending(std::monostate{}, before);
    StagedChange change;
    if (!worker->lease_id.empty()) {
      stage_lease_end(change, worker->lease_id, false);
      notify = callbacks_;
    }
    WorkerEntry& staged = change.worker(*worker);
    staged.info.state = WorkerState::left;
    staged.info.last_seen_ms = clock_.now_ms();
    commit(change);
    spdlog::info("worker {} ({}) left", worker_id, worker->info.name);
    answer = pending(std::monostate{}, before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

void Scheduler::forget_workers_locked(std::int64_t now) {
  if (config_.forget_workers_after_ms <= 0) return;
  for (auto it = workers_.begin(); it != workers_.end();) {
    const WorkerEntry& worker = *it->second;
    if (is_present(worker.info.state) || !worker.lease_id.empty() ||
        now - worker.info.last_seen_ms < config_.forget_workers_after_ms) {
      ++it;
      continue;
    }
    spdlog::info("worker {} ({}) forgotten: {} since {} s ago", it->first, worker.info.name,
                 to_string(worker.info.state), (now - worker.info.last_seen_ms) / 1000);
    queue_write([id = it->first](Store& store) { store.delete_worker(id); });
    secret_owners_.erase(worker.secret_sha256);
    it = workers_.erase(it);
  }
}

std::vector<WorkerRecord> Scheduler::workers() const {
  std::lock_guard lock(mutex_);
  std::vector<WorkerRecord> result;
  result.reserve(workers_.size());
  const std::int64_t now = clock_.now_ms();
  for (const auto& [id, worker] : workers_) {
    WorkerRecord& info = result.emplace_back(worker->info);
    int tiles = 0;
    std::uint64_t rays = 0;
    for (const auto& [when, count, traced] : worker->recent) {
      if (when < now - 60'000) continue;
      tiles += count;
      rays += traced;
    }
    info.tiles_per_min = tiles;
    info.rays_per_s = static_cast<double>(rays) / 60;
  }
  std::sort(result.begin(), result.end(), [](const WorkerRecord& a, const WorkerRecord& b) {
    return a.name != b.name ? a.name < b.name : a.id < b.id;
  });
  return result;
}

void Scheduler::on_work_available(std::function<void()> callback) {
  std::lock_guard lock(mutex_);
  callbacks_.push_back(std::move(callback));
}

void Scheduler::on_job_finished(std::function<void()> callback) {
  std::lock_guard lock(mutex_);
  finished_callbacks_.push_back(std::move(callback));
}

void Scheduler::note_seen(WorkerEntry& worker, std::int64_t now) {
  worker.info.last_seen_ms = now;
  if (now - worker.persisted_seen_ms < seen_write_interval_ms) return;
  queue_write([id = worker.info.id, now](Store& store) { store.update_worker_seen(id, now); });
  worker.persisted_seen_ms = now;
}

SharedText Scheduler::worker_text(const std::string& id) const {
  const WorkerEntry* worker = find_worker(id);
  return worker ? worker->id_text : SharedText(id);
}

}  // namespace tessera
