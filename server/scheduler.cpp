// The Scheduler's job side: submitting, listing, canceling, removing and assembling jobs.
// Leases are in scheduler_leases.cpp, workers in scheduler_workers.cpp, start-up in
// scheduler_load.cpp and the bookkeeping every change goes through in scheduler_commit.cpp.
#include <spdlog/spdlog.h>

#include "server/scheduler.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>

#include "server/ids.hpp"
#include "server/scheduler_entries.hpp"

namespace tessera {

Scheduler::Scheduler(Store& store, const Clock& clock, SchedulerConfig config)
    : store_(store), clock_(clock), config_(config) {
  {
    std::lock_guard lock(mutex_);
    load_and_reconcile();
  }
  image_thread_ = std::thread([this] { write_images(); });
}

Scheduler::~Scheduler() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  images_changed_.notify_all();
  image_thread_.join();  // after the images still queued are written
}

JobEntry* Scheduler::find_job(const std::string& id) const {
  const auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second.get();
}

WorkerEntry* Scheduler::find_worker(const std::string& id) const {
  const auto it = workers_.find(id);
  return it == workers_.end() ? nullptr : it->second.get();
}

JobStatus Scheduler::submit(const std::string& name, int priority, const Scene& scene,
                            const std::string& scene_json) {
  // Outside the lock: hashing a large mesh scene takes a while.
  const std::string digest = sha256_hex(scene_json);
  const std::vector<TileRect> rects =
      split_into_tiles(scene.width, scene.height, scene.render.tile_size);

  Callbacks notify;
  JobStatus result;
  {
    std::lock_guard lock(mutex_);
    auto job = std::make_unique<JobEntry>();
    JobStatus& s = job->status;
    do {
      s.id = "j-" + random_hex(32);  // 128 bits: nobody finds a job by guessing its id
    } while (jobs_.contains(s.id));
    s.name = name;
    s.state = JobState::queued;
    s.priority = priority;
    s.width = scene.width;
    s.height = scene.height;
    s.tile_size = scene.render.tile_size;
    s.created_at_ms = clock_.now_ms();
    s.scene_digest = digest;

    std::vector<TileRow> rows;
    rows.reserve(rects.size());
    job->tiles.reserve(rects.size());
    for (const TileRect& rect : rects) {
      TileSlot& tile = job->tiles.emplace_back();
      tile.rect = rect;
      rows.push_back(tile_row(s.id, static_cast<int>(rows.size()), tile));
    }
    store_.insert_job(job_row(s), scene_json, rows);

    JobEntry& entry = *jobs_.emplace(s.id, std::move(job)).first->second;
    index_tiles(entry);
    result = entry.status;
    notify = callbacks_;
  }
  spdlog::info("job {} ({}): submitted, {}x{} in {} tiles, priority {}", result.id, result.name,
               result.width, result.height, result.tiles_total, result.priority);
  for (const auto& callback : notify) callback();
  return result;
}

std::optional<JobStatus> Scheduler::job(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  if (!job) return std::nullopt;
  return job->status;
}

std::vector<JobStatus> Scheduler::jobs(std::optional<JobState> state, std::size_t limit) const {
  std::lock_guard lock(mutex_);
  std::vector<const JobStatus*> matching;
  for (const auto& [id, job] : jobs_)
    if (!state || job->status.state == *state) matching.push_back(&job->status);
  const auto newest_first = [](const JobStatus* a, const JobStatus* b) {
    if (a->created_at_ms != b->created_at_ms) return a->created_at_ms > b->created_at_ms;
    return a->id > b->id;
  };
  const std::size_t count = std::min(limit, matching.size());
  std::partial_sort(matching.begin(), matching.begin() + static_cast<std::ptrdiff_t>(count),
                    matching.end(), newest_first);
  std::vector<JobStatus> result;
  result.reserve(count);
  for (std::size_t i = 0; i < count; ++i) result.push_back(*matching[i]);
  return result;
}

CancelOutcome Scheduler::cancel(const std::string& id) {
  std::lock_guard lock(mutex_);
  JobEntry* job = find_job(id);
  if (!job) return CancelOutcome::not_found;
  if (is_finished(job->status.state)) return CancelOutcome::already_finished;
  StagedChange change;
  JobStatus& status = change.job(*job);
  status.state = JobState::canceled;
  status.finished_at_ms = clock_.now_ms();
  // Withdrawn leases are forgotten: their heartbeats answer "lost", their results "stale".
  for (const TileSlot& tile : job->tiles)
    if (!tile.lease_id.empty()) stage_lease_end(change, tile.lease_id, false);
  commit(change);
  return CancelOutcome::canceled;
}

RemoveOutcome Scheduler::remove(const std::string& id) {
  std::lock_guard lock(mutex_);
  JobEntry* job = find_job(id);
  if (!job) return RemoveOutcome::not_found;
  if (!is_finished(job->status.state)) return RemoveOutcome::not_finished;
  store_.delete_job(id);
  // A finished job holds no leases; only its delivered lease ids are indexed.
  for (int index = 0; index < job->status.tiles_total; ++index) track_tile(*job, index, -1);
  jobs_.erase(id);
  return RemoveOutcome::removed;
}

std::optional<std::string> Scheduler::scene_json(const std::string& digest) const {
  std::lock_guard lock(mutex_);
  return store_.scene_json(digest);
}

std::shared_ptr<const Image> Scheduler::assemble(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  if (!job) return nullptr;
  // Only a finished job's canvas is safe to share: a running one still takes tiles.
  if (job->canvas && is_finished(job->status.state)) return job->canvas;
  if (job->canvas) return std::make_shared<const Image>(*job->canvas);
  return std::make_shared<const Image>(assemble_locked(*job));
}

Image& Scheduler::canvas_of(JobEntry& job) {
  if (!job.canvas) job.canvas = std::make_shared<Image>(assemble_locked(job));
  return *job.canvas;
}

Image Scheduler::assemble_locked(const JobEntry& job) const {
  Image image(job.status.width, job.status.height);
  store_.for_each_tile_pixels(job.status.id, [&](int index, std::span<const float> pixels) {
    if (index < 0 || index >= static_cast<int>(job.tiles.size()))
      throw std::runtime_error("job " + job.status.id + ": stored pixels for unknown tile " +
                               std::to_string(index));
    // Only a done tile's pixels are the accepted result.
    if (job.tiles[index].state == TileState::done) image.paste(job.tiles[index].rect, pixels);
  });
  return image;
}

void Scheduler::wait_for_images() {
  std::unique_lock lock(mutex_);
  images_changed_.wait(lock, [&] { return images_to_write_.empty() && !writing_image_; });
}

void Scheduler::write_images() {
  // Below the threads that answer requests and render: an image file is for later.
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);
  std::unique_lock lock(mutex_);
  while (true) {
    images_changed_.wait(lock, [&] { return stopping_ || !images_to_write_.empty(); });
    if (images_to_write_.empty()) return;  // stopping, and nothing is left to write
    const std::string id = std::move(images_to_write_.front());
    images_to_write_.pop_front();
    const JobEntry* job = find_job(id);
    if (!job || job->status.state != JobState::completed) continue;
    writing_image_ = true;
    std::string error;
    try {
      // A completed job's canvas changes no more, so it can be read outside the lock.
      const std::shared_ptr<const Image> image =
          job->canvas ? job->canvas : std::make_shared<const Image>(assemble_locked(*job));
      // Encoding takes a while and touches no shared state: workers and clients go on.
      lock.unlock();
      store_.write_image(id, *image);
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (!lock.owns_lock()) lock.lock();
    writing_image_ = false;
    images_changed_.notify_all();
    JobEntry* still = find_job(id);
    if (!still) {
      store_.remove_image(id);  // removed while it was being written
      continue;
    }
    still->canvas.reset();  // the file (or the store) serves it from now on
    if (!error.empty() && still->status.state == JobState::completed) {
      // Every tile is stored, so a resubmission renders again; a "completed" job without
      // an image file would only fail later, when someone looks for it.
      StagedChange change;
      JobStatus& status = change.job(*still);
      status.state = JobState::failed;
      status.error = "cannot write the image: " + error;
      commit(change);
    }
  }
}

}  // namespace tessera
