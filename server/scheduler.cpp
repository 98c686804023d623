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
#include "server/tile_order.hpp"

namespace tessera {

Scheduler::Scheduler(Store& store, const Clock& clock, SchedulerConfig config)
    : store_(store), images_(store.data_dir()), clock_(clock), config_(config) {
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
  // Also outside: sorting a million tiles takes a while too.
  std::vector<int> order = centre_first_order(rects, scene.width, scene.height);

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
    s.output_transfer = scene.render.output_transfer;

    job->tiles.resize(rects.size());
    for (std::size_t i = 0; i < rects.size(); ++i) job->tiles[i].rect = rects[i];
    store_.insert_job(job_row(s), scene_json);

    JobEntry& entry = *jobs_.emplace(s.id, std::move(job)).first->second;
    index_tiles(entry, std::move(order));
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
  // After the job's rows: a file left behind by a failure here is pruned on the next start,
  // while a row without its image would be a completed job that cannot be served.
  images_.remove(id);
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

std::optional<std::filesystem::path> Scheduler::image_file(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  // The file appears whole (it is written beside its place and renamed), so once it is
  // there it can be sent.
  if (!job || job->status.state != JobState::completed || !images_.has(id)) return std::nullopt;
  return images_.path(id);
}

void Scheduler::make_canvas(std::unique_lock<std::mutex>& lock, const std::string& id) {
  JobEntry* job = find_job(id);
  if (!job || job->canvas || job->canvas_coming) return;
  job->canvas_coming = true;
  const int width = job->status.width;
  const int height = job->status.height;
  lock.unlock();
  auto canvas = std::make_shared<Image>(width, height);
  lock.lock();
  job = find_job(id);  // it may have been removed meanwhile
  if (!job) return;
  job->canvas_coming = false;
  images_changed_.notify_all();  // the image thread may wait for it
  // A failed or canceled job's image comes from the store; a completed one's canvas is
  // taken by the image thread, which waited for it.
  if (job->status.state == JobState::failed || job->status.state == JobState::canceled) return;
  // Every result accepted so far is stored, those of the requests served meanwhile too.
  paste_stored(*canvas, *job);
  job->canvas = std::move(canvas);
}

Image Scheduler::assemble_locked(const JobEntry& job) const {
  Image image(job.status.width, job.status.height);
  paste_stored(image, job);
  return image;
}

void Scheduler::paste_stored(Image& image, const JobEntry& job) const {
  const auto floats_of = [&](int index) -> std::size_t {
    if (index < 0 || index >= static_cast<int>(job.tiles.size()))
      throw std::runtime_error("job " + job.status.id + ": stored pixels for unknown tile " +
                               std::to_string(index));
    return job.tiles[index].rect.pixel_count() * 3;
  };
  store_.for_each_tile_pixels(job.status.id, floats_of,
                              [&](int index, std::span<const float> pixels) {
                                // Only a done tile's pixels are the accepted result.
                                if (job.tiles[index].state == TileState::done)
                                  image.paste(job.tiles[index].rect, pixels);
                              });
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
    writing_image_ = true;
    // A canvas on its way is waited for, rather than assembling a second one from the store.
    const JobEntry* job = find_job(id);
    while (job && job->canvas_coming) {
      images_changed_.wait(lock);
      job = find_job(id);
    }
    if (!job || job->status.state != JobState::completed) {
      writing_image_ = false;
      images_changed_.notify_all();
      continue;
    }
    std::string error;
    try {
      // A completed job's canvas changes no more, so it can be read outside the lock.
      const std::shared_ptr<const Image> image =
          job->canvas ? job->canvas : std::make_shared<const Image>(assemble_locked(*job));
      // Encoding takes a while and touches no shared state: workers and clients go on.
      lock.unlock();
      images_.write(id, *image);
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (!lock.owns_lock()) lock.lock();
    writing_image_ = false;
    images_changed_.notify_all();
    JobEntry* still = find_job(id);
    if (!still) {
      images_.remove(id);  // removed while it was being written
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
