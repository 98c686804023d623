// The Scheduler's job side: submitting, listing, canceling, removing and assembling jobs.
// Leases are in scheduler_leases.cpp, workers in scheduler_workers.cpp, start-up in
// scheduler_load.cpp and the bookkeeping every change goes through in scheduler_commit.cpp;
// images are ImageAssembly's.
#include <spdlog/spdlog.h>

#include "server/scheduler.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>

#include "server/ids.hpp"
#include "server/scheduler_entries.hpp"
#include "server/tile_order.hpp"

namespace tessera {

Scheduler::Scheduler(Store& store, const Clock& clock, SchedulerConfig config)
    : store_(store),
      clock_(clock),
      config_(config),
      store_thread_(store),
      images_(store.data_dir(), store_thread_,
              [this](const std::string& id, const std::string& error) {
                image_write_failed(id, error);
              }) {
  StoreTicket loaded = 0;
  {
    // The store thread has nothing to do yet, so this thread may read the Store.
    std::lock_guard lock(mutex_);
    load_and_reconcile();
    loaded = last_write_;
  }
  // What reconciling changed is durable before anyone is answered.
  if (const std::string error = store_thread_.wait(loaded); !error.empty())
    throw std::runtime_error("cannot store the state reconciled at start: " + error);
}

Scheduler::~Scheduler() {
  // What is queued may queue images to write; the image thread writes them and may queue
  // a job's failure, whose callbacks use images_: all of it is done before images_ goes.
  store_thread_.wait(store_thread_.last());
  images_.stop();
  store_thread_.wait(store_thread_.last());
}

void Scheduler::when_stored(StoreTicket ticket, bool wrote, StoreThread::Done done) {
  store_thread_.after(ticket, [wrote, done = std::move(done)](const std::string& error) {
    done(wrote ? error : std::string());
  });
}

Written Scheduler::durable() const {
  std::lock_guard lock(mutex_);
  return {{}, last_write_, false};
}

std::string Scheduler::wait_stored(StoreTicket ticket, bool wrote) {
  const std::string error = store_thread_.wait(ticket);
  return wrote ? error : std::string();
}

JobEntry* Scheduler::find_job(const std::string& id) const {
  const auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second.get();
}

WorkerEntry* Scheduler::find_worker(const std::string& id) const {
  const auto it = workers_.find(id);
  return it == workers_.end() ? nullptr : it->second.get();
}

void Scheduler::submit(const std::string& name, int priority, const Scene& scene,
                       std::string scene_json, Submitted then) {
  // Outside the lock: hashing a large mesh scene takes a while.
  const std::string digest = sha256_hex(scene_json);
  const std::vector<TileRect> rects =
      split_into_tiles(scene.width, scene.height, scene.render.tile_size);
  // Also outside: sorting a million tiles takes a while too.
  std::vector<int> order = centre_first_order(rects, scene.width, scene.height);

  auto job = std::make_shared<JobEntry>();
  JobStatus& s = job->status;
  s.name = name;
  s.state = JobState::queued;
  s.priority = priority;
  s.width = scene.width;
  s.height = scene.height;
  s.tile_size = scene.render.tile_size;
  s.created_at_ms = clock_.now_ms();
  s.scene_digest = digest;
  s.output_transfer = scene.render.output_transfer;
  job->tiles.resize(rects.size());
  for (std::size_t i = 0; i < rects.size(); ++i) job->tiles[i].rect = rects[i];
  std::shared_ptr<const Frame> frame = frame_of(*job);  // outside the lock too

  StoreTicket ticket = 0;
  {
    std::lock_guard lock(mutex_);
    do {
      s.id = "j-" + random_hex(32);  // 128 bits: nobody finds a job by guessing its id
    } while (jobs_.contains(s.id));
    ticket = queue_write(
        [row = job_row(s), json = std::make_shared<const std::string>(std::move(scene_json))](
            Store& store) { store.insert_job(row, *json); });
  }
  // Nothing can lease a tile of the job, nor list it, before it is stored: a job the store
  // refuses (a full disk, say) leaves nothing behind.
  store_thread_.after(ticket, [this, job, order = std::move(order), frame = std::move(frame),
                               then = std::move(then)](const std::string& error) mutable {
    if (!error.empty()) {
      spdlog::error("job {} ({}): cannot store it: {}", job->status.id, job->status.name, error);
      return then(std::nullopt, error);
    }
    Callbacks notify;
    JobStatus status;
    FarmObserver* observer = nullptr;
    {
      std::lock_guard lock(mutex_);
      observer = observer_;
      const std::string id = job->status.id;
      JobEntry& entry =
          *jobs_.emplace(id, std::make_unique<JobEntry>(std::move(*job))).first->second;
      index_tiles(entry, std::move(order));
      images_.add(id, std::move(frame));
      status = entry.status;
      notify = callbacks_;
    }
    spdlog::info("job {} ({}): submitted, {}x{} in {} tiles, priority {}", status.id, status.name,
                 status.width, status.height, status.tiles_total, status.priority);
    if (observer) observer->jobs_changed({status});
    for (const auto& callback : notify) callback();
    then(status, "");
  });
}

std::optional<JobStatus> Scheduler::job(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  if (!job) return std::nullopt;
  return job->status;
}

std::vector<JobStatus> Scheduler::jobs(std::optional<JobState> state, std::size_t limit,
                                       std::size_t offset) const {
  std::lock_guard lock(mutex_);
  std::vector<const JobStatus*> matching;
  for (const auto& [id, job] : jobs_)
    if (!state || job->status.state == *state) matching.push_back(&job->status);
  const auto newest_first = [](const JobStatus* a, const JobStatus* b) {
    if (a->created_at_ms != b->created_at_ms) return a->created_at_ms > b->created_at_ms;
    return a->id > b->id;
  };
  // Sorted only as far as the page reaches: a page of a long list costs no full sort.
  const std::size_t end = std::min(offset + limit, matching.size());
  std::partial_sort(matching.begin(), matching.begin() + static_cast<std::ptrdiff_t>(end),
                    matching.end(), newest_first);
  std::vector<JobStatus> result;
  for (std::size_t i = std::min(offset, end); i < end; ++i) result.push_back(*matching[i]);
  return result;
}

Pending<CancelOutcome> Scheduler::cancel(const std::string& id) {
  std::lock_guard lock(mutex_);
  const StoreTicket before = last_write_;
  JobEntry* job = find_job(id);
  if (!job) return pending(CancelOutcome::not_found, before);
  if (is_finished(job->status.state)) return pending(CancelOutcome::already_finished, before);
  StagedChange change;
  JobStatus& status = change.job(*job);
  status.state = JobState::canceled;
  status.finished_at_ms = clock_.now_ms();
  // Withdrawn leases are forgotten: their heartbeats answer "lost", their results "stale".
  for (const TileSlot& tile : job->tiles)
    if (!tile.lease_id.empty()) stage_lease_end(change, tile.lease_id, false);
  commit(change);
  return pending(CancelOutcome::canceled, before);
}

Pending<RemoveOutcome> Scheduler::remove(const std::string& id) {
  std::lock_guard lock(mutex_);
  const StoreTicket before = last_write_;
  JobEntry* job = find_job(id);
  if (!job) return pending(RemoveOutcome::not_found, before);
  if (!is_finished(job->status.state)) return pending(RemoveOutcome::not_finished, before);
  const StoreTicket ticket = queue_write([id](Store& store) { store.delete_job(id); });
  // After the job's rows: a file left behind by a failure here is pruned on the next start,
  // while a row without its image would be a completed job that cannot be served.
  store_thread_.after(ticket, [this, id, observer = observer_](const std::string& error) {
    if (!error.empty()) return;
    images_.removed(id);
    if (observer) observer->job_removed(id);
  });
  // A finished job holds no leases; only its delivered lease ids are indexed.
  for (int index = 0; index < job->status.tiles_total; ++index) track_tile(*job, index, -1);
  jobs_.erase(id);
  return pending(RemoveOutcome::removed, before);
}

void Scheduler::scene_json(const std::string& digest,
                           std::function<void(std::optional<std::string>)> then) const {
  store_thread_.read(
      [digest, then = std::move(then)](Store& store) { then(store.scene_json(digest)); });
}

void Scheduler::assemble(const std::string& id,
                         std::function<void(std::shared_ptr<const Image>)> then) const {
  bool finished = false;
  {
    std::lock_guard lock(mutex_);
    const JobEntry* job = find_job(id);
    finished = job != nullptr && job->status.state == JobState::completed;
  }
  images_.assemble(id, std::move(then), finished);
}

std::optional<std::filesystem::path> Scheduler::image_file(const std::string& id) const {
  return images_.image_file(id);
}

void Scheduler::wait_for_images() {
  // Completing writes hand their images over once durable.
  store_thread_.wait(store_thread_.last());
  images_.wait_for_images();
}

void Scheduler::image_write_failed(const std::string& id, const std::string& error) {
  std::lock_guard lock(mutex_);
  JobEntry* job = find_job(id);
  if (!job || job->status.state != JobState::completed) return;
  StagedChange change;
  JobStatus& status = change.job(*job);
  status.state = JobState::failed;
  status.error = "cannot write the image: " + error;
  commit(change);
}

void Scheduler::stop_notifying() {
  {
    std::lock_guard lock(mutex_);
    callbacks_.clear();
    finished_callbacks_.clear();
  }
  wait_for_images();
}

}  // namespace tessera
