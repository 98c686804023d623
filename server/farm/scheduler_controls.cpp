// The farm's controls: a job's priority, pausing and resuming it, retrying a failed one,
// draining and removing workers. Each is one staged change, as every other state change.
#include <algorithm>
#include <memory>

#include <spdlog/spdlog.h>

#include "server/farm/scheduler.hpp"
#include "server/farm/scheduler_entries.hpp"

namespace tessera {
namespace {

ControlOutcome refused(std::string code, std::string message) {
  return {ControlOutcome::Result::refused, std::move(code), std::move(message)};
}

const ControlOutcome not_found{ControlOutcome::Result::not_found, {}, {}};
const ControlOutcome done{};

ControlOutcome finished(const JobRecord& job) {
  return refused("already_finished",
                 "job " + job.id + " has already " + std::string(to_string(job.state)));
}

}  // namespace

template <typename Change>
Pending<ControlOutcome> Scheduler::control_job(const std::string& id, Change change_job,
                                               std::function<void()> durable) {
  Callbacks notify;
  Pending<ControlOutcome> answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    JobEntry* job = find_job(id);
    if (!job) return pending(not_found, before);
    StagedChange change;
    if (const std::optional<ControlOutcome> refusal = change_job(*job, change))
      return pending(*refusal, before);
    if (!change.empty()) {
      const StoreTicket ticket = commit(change);
      if (durable)
        store_thread_.after(ticket, [durable = std::move(durable)](const std::string& error) {
          if (error.empty()) durable();
        });
      notify = callbacks_;  // a claim waiting for work may take it now
    }
    answer = pending(done, before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

Pending<ControlOutcome> Scheduler::set_priority(const std::string& id, int priority) {
  return control_job(id, [&](JobEntry& job, StagedChange& change) -> std::optional<ControlOutcome> {
    if (is_finished(job.status.state)) return finished(job.status);
    if (job.status.priority == priority) return std::nullopt;
    change.job(job).priority = priority;
    spdlog::info("job {} ({}): priority {}", id, job.status.name, priority);
    return std::nullopt;
  });
}

Pending<ControlOutcome> Scheduler::pause(const std::string& id) {
  return control_job(id, [](JobEntry& job, StagedChange& change) -> std::optional<ControlOutcome> {
    if (is_finished(job.status.state)) return finished(job.status);
    if (job.status.state != JobState::paused) change.job(job).state = JobState::paused;
    return std::nullopt;
  });
}

Pending<ControlOutcome> Scheduler::resume(const std::string& id) {
  return control_job(id, [&](JobEntry& job, StagedChange& change) -> std::optional<ControlOutcome> {
    if (is_finished(job.status.state)) return finished(job.status);
    if (job.status.state != JobState::paused) return std::nullopt;
    JobRecord& status = change.job(job);
    status.state = status.started_at_ms != 0 ? JobState::running : JobState::queued;
    // The stall clock counts from now: the pause was asked for, not a stall.
    job.status.health.progress_at_ms = clock_.now_ms();
    return std::nullopt;
  });
}

Pending<ControlOutcome> Scheduler::retry(const std::string& id) {
  // Done frames whose image is written again once the retry is durable, as after a
  // completion: a write that fails then finds the job completed (or running) and fails it
  // once more, with the reason.
  auto rewrite = std::make_shared<std::vector<std::string>>();
  return control_job(
      id,
      [&](JobEntry& job, StagedChange& change) -> std::optional<ControlOutcome> {
        // A canceled job comes back as well: canceled by mistake, or to finish it after
        // all, it renders what it lacked, keeping its id, its links and its tiles done.
        if (job.status.state != JobState::failed && job.status.state != JobState::canceled)
          return refused("not_failed", "job " + id + " is " + to_string(job.status.state) +
                                           "; only a failed or canceled job is retried");
        int again = 0;
        for (int index = 0; index < job.status.tiles_total; ++index) {
          const TileSlot& tile = job.tiles[index];
          if (tile.state == TileState::done) continue;
          ++again;
          if (tile.attempts == 0 && tile.last_error.empty() && tile.handouts == 0) continue;
          TileSlot& staged = change.tile(job, index);
          staged.attempts = 0;
          staged.last_error.clear();
          staged.handouts = 0;
        }
        // Every tile done: it failed for want of its image (a full disk, say), and it is
        // completed again; the image is written from the stored tiles, and should that
        // fail once more, it fails once more.
        JobRecord& status = change.job(job);
        status.state = again == 0                  ? JobState::completed
                       : status.started_at_ms != 0 ? JobState::running
                                                   : JobState::queued;
        status.error.clear();
        status.finished_at_ms = again == 0 ? clock_.now_ms() : 0;
        // What went wrong before is in the log; the retried job starts with a clean record.
        job.status.health = JobHealthRecord{};
        job.status.health.progress_at_ms = clock_.now_ms();
        job.failures_by_worker.clear();
        for (int slot = 0; slot < job.frame_count(); ++slot) {
          const std::string key = image_key(job, slot);
          // Its unfinished frames' tiles go to a canvas again as they arrive; its frames
          // done keep their images, or have them written now.
          if (job.frame_done[slot] < job.tiles_per_frame)
            images_.resumed(key);
          else if (!images_.has_file(key))
            rewrite->push_back(key);
        }
        spdlog::info("job {} ({}): retrying {} tile(s){}", id, job.status.name, again,
                     rewrite->empty() ? "" : fmt::format(", writing {} image(s)", rewrite->size()));
        return std::nullopt;
      },
      [this, rewrite] {
        for (const std::string& key : *rewrite) images_.completed(key);
      });
}

std::vector<std::string> Scheduler::job_ids_with_prefix(const std::string& prefix,
                                                        std::size_t limit) const {
  std::vector<std::string> ids;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, job] : jobs_)
      if (id.starts_with(prefix)) ids.push_back(id);
  }
  std::sort(ids.begin(), ids.end());
  if (ids.size() > limit) ids.resize(limit);
  return ids;
}

Pending<ControlOutcome> Scheduler::drain_worker(const std::string& worker_id, bool draining) {
  Callbacks notify;
  Pending<ControlOutcome> answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    WorkerEntry* worker = find_worker(worker_id);
    if (!worker) return pending(not_found, before);
    if (worker->info.draining != draining) {
      StagedChange change;
      change.worker(*worker).info.draining = draining;
      commit(change);
      spdlog::info("worker {} ({}): {}", worker_id, worker->info.name,
                   draining ? "draining" : "no longer draining");
      if (!draining) notify = callbacks_;  // its waiting claim may take work now
    }
    answer = pending(done, before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

Pending<ControlOutcome> Scheduler::remove_worker(const std::string& worker_id) {
  Callbacks notify;
  Pending<ControlOutcome> answer;
  {
    std::lock_guard lock(mutex_);
    const StoreTicket before = last_write_;
    WorkerEntry* worker = find_worker(worker_id);
    if (!worker) return pending(not_found, before);
    if (!worker->lease_id.empty()) {
      StagedChange change;
      stage_lease_end(change, worker->lease_id, false);
      commit(change);
      notify = callbacks_;
    }
    spdlog::info("worker {} ({}) removed", worker_id, worker->info.name);
    const StoreTicket ticket =
        queue_write([id = worker_id](Store& store) { store.delete_worker(id); });
    if (observer_)
      store_thread_.after(
          ticket, [observer = observer_, info = worker->info](const std::string& error) {
            if (error.empty())
              observer->workers_changed({{info, FarmObserver::WorkerChange::removed}});
          });
    present_workers_ -= static_cast<int>(is_present(worker->info.state));
    secret_owners_.erase(worker->secret_sha256);
    workers_.erase(worker_id);
    answer = pending(done, before);
  }
  for (const auto& callback : notify) callback();
  return answer;
}

FarmGauges Scheduler::gauges() const {
  FarmGauges gauges;
  for (const auto& [state, name] : protocol::kJobStateNames) gauges.jobs[state] = 0;
  for (const auto& [state, name] : protocol::kWorkerStateNames)
    gauges.workers[std::string(name)] = 0;
  gauges.workers["draining"] = 0;
  std::lock_guard lock(mutex_);
  for (const auto& [id, job] : jobs_) {
    gauges.jobs[job->status.state] += 1;
    if (hands_out_tiles(job->status.state))
      gauges.pending_by_priority[job->status.priority] += job->pending.size();
  }
  for (const auto& [id, worker] : workers_) {
    gauges.workers[to_string(worker->info.state)] += 1;
    if (worker->info.draining) gauges.workers["draining"] += 1;
  }
  return gauges;
}

}  // namespace tessera
