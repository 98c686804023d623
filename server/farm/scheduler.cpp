// The Scheduler's job side: submitting, listing, canceling, removing and assembling jobs.
// Leases are in scheduler_leases.cpp, workers in scheduler_workers.cpp, start-up in
// scheduler_load.cpp and the bookkeeping every change goes through in scheduler_commit.cpp;
// images are ImageAssembly's.
#include <spdlog/spdlog.h>

#include "server/farm/scheduler.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>

#include "common/scene/frame_list.hpp"
#include "server/farm/ids.hpp"
#include "server/farm/scheduler_entries.hpp"
#include "server/farm/tile_order.hpp"

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
                       std::string scene_json, Submitted then, std::vector<int> frames) {
  // Outside the lock: hashing a large mesh scene takes a while.
  const std::string digest = sha256_hex(scene_json);
  // Made once, and shared by the job: every frame is cut alike.
  auto rects = std::make_shared<const std::vector<TileRect>>(
      split_into_tiles(scene.width, scene.height, scene.render.tile_size));
  auto job_frames = std::make_shared<JobFrames>();
  if (frames.empty()) {
    job_frames->numbers = {0};
  } else {
    job_frames->list = format_frame_list(frames);
    job_frames->numbers = std::move(frames);
  }
  const int frame_count = static_cast<int>(job_frames->numbers.size());
  // Also outside: sorting a million tiles takes a while too.
  std::vector<int> order = hand_out_order(*rects, scene.width, scene.height, frame_count);

  auto job = std::make_shared<JobEntry>();
  JobRecord& s = job->status;
  s.name = name;
  s.state = JobState::queued;
  s.priority = priority;
  s.width = scene.width;
  s.height = scene.height;
  s.tile_size = scene.render.tile_size;
  s.created_at_ms = clock_.now_ms();
  s.scene_digest = digest;
  s.output_transfer = scene.render.output_transfer;
  s.frames = std::move(job_frames);
  job->tiles_per_frame = static_cast<int>(rects->size());
  job->tiles.resize(rects->size() * frame_count);
  job->rects = std::move(rects);

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
  store_thread_.after(ticket, [this, job, order = std::move(order),
                               then = std::move(then)](const std::string& error) mutable {
    if (!error.empty()) {
      spdlog::error("job {} ({}): cannot store it: {}", job->status.id, job->status.name, error);
      return then(std::nullopt, error);
    }
    Callbacks notify;
    JobRecord status;
    FarmObserver* observer = nullptr;
    {
      std::lock_guard lock(mutex_);
      observer = observer_;
      const std::string id = job->status.id;
      JobEntry& entry =
          *jobs_.emplace(id, std::make_unique<JobEntry>(std::move(*job))).first->second;
      job_memory_ += entry.tiles.size() * kTileBytes;
      index_tiles(entry, std::move(order));
      const std::vector<std::shared_ptr<const Frame>> images = frames_of(entry);
      for (int slot = 0; slot < entry.frame_count(); ++slot)
        images_.add(image_key(entry, slot), images[slot]);
      status = entry.status;
      notify = callbacks_;
    }
    if (status.frames->animated())
      spdlog::info("job {} ({}): submitted, frames {} at {}x{} in {} tiles, priority {}", status.id,
                   status.name, status.frames->list, status.width, status.height,
                   status.tiles_total, status.priority);
    else
      spdlog::info("job {} ({}): submitted, {}x{} in {} tiles, priority {}", status.id, status.name,
                   status.width, status.height, status.tiles_total, status.priority);
    if (observer) observer->jobs_changed({status});
    for (const auto& callback : notify) callback();
    then(status, "");
  });
}

std::optional<std::string> Scheduler::job_memory_refusal(std::uint64_t tiles) const {
  const std::uint64_t budget = config_.job_memory_budget;
  const std::uint64_t held = job_memory_.load();
  const std::uint64_t wanted = tiles * kTileBytes;
  if (budget == 0 || held + wanted <= budget) return std::nullopt;
  const auto mib = [](std::uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; };
  return "its " + std::to_string(tiles) + " tiles would take " + mib(wanted) +
         " of the coordinator's memory beside the " + mib(held) +
         " its jobs hold, more than --job-memory-budget (" + mib(budget) +
         "); remove finished jobs (tessera rm), or render it in fewer, larger tiles";
}

std::optional<JobRecord> Scheduler::job(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  if (!job) return std::nullopt;
  return job->status;
}

std::vector<JobRecord> Scheduler::jobs(std::optional<JobState> state, std::size_t limit,
                                       std::size_t offset,
                                       const std::optional<std::string>& name) const {
  std::lock_guard lock(mutex_);
  std::vector<const JobRecord*> matching;
  for (const auto& [id, job] : jobs_)
    if ((!state || job->status.state == *state) && (!name || job->status.name == *name))
      matching.push_back(&job->status);
  const auto newest_first = [](const JobRecord* a, const JobRecord* b) {
    if (a->created_at_ms != b->created_at_ms) return a->created_at_ms > b->created_at_ms;
    return a->id > b->id;
  };
  // Sorted only as far as the page reaches: a page of a long list costs no full sort.
  const std::size_t end = std::min(offset + limit, matching.size());
  std::partial_sort(matching.begin(), matching.begin() + static_cast<std::ptrdiff_t>(end),
                    matching.end(), newest_first);
  std::vector<JobRecord> result;
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
  JobRecord& status = change.job(*job);
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
  std::vector<std::string> keys;
  for (int slot = 0; slot < job->frame_count(); ++slot) keys.push_back(image_key(*job, slot));
  store_thread_.after(
      ticket, [this, id, keys = std::move(keys), observer = observer_](const std::string& error) {
        if (!error.empty()) return;
        for (const std::string& key : keys) images_.removed(key);
        if (observer) observer->job_removed(id);
      });
  // A finished job holds no leases; only its delivered lease ids are indexed.
  for (int index = 0; index < job->status.tiles_total; ++index) track_tile(*job, index, -1);
  job_memory_ -= job->tiles.size() * kTileBytes;
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
  // An animation's image is its first frame's.
  const std::optional<int> first = first_frame(id);
  if (!first) return then(nullptr);
  assemble_frame(id, *first, std::move(then));
}

std::optional<std::filesystem::path> Scheduler::image_file(const std::string& id) const {
  const std::optional<int> first = first_frame(id);
  if (!first) return std::nullopt;
  return frame_image_file(id, *first);
}

std::optional<int> Scheduler::first_frame(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  if (!job) return std::nullopt;
  return job->status.frames->numbers.front();
}

void Scheduler::assemble_frame(const std::string& id, int frame,
                               std::function<void(std::shared_ptr<const Image>)> then) const {
  std::string key;
  bool finished = false;
  {
    std::lock_guard lock(mutex_);
    const JobEntry* job = find_job(id);
    const std::optional<int> slot = job ? slot_of_frame(*job, frame) : std::nullopt;
    if (!slot) return then(nullptr);
    key = image_key(*job, *slot);
    // Done: its observers may have heard so before the write's callbacks pasted its last
    // tiles (ImageAssembly::assemble()).
    finished = job->frame_done[*slot] == job->tiles_per_frame;
  }
  images_.assemble(key, std::move(then), finished);
}

std::optional<std::filesystem::path> Scheduler::frame_image_file(const std::string& id,
                                                                 int frame) const {
  std::string key;
  {
    std::lock_guard lock(mutex_);
    const JobEntry* job = find_job(id);
    const std::optional<int> slot = job ? slot_of_frame(*job, frame) : std::nullopt;
    if (!slot) return std::nullopt;
    key = image_key(*job, *slot);
  }
  return images_.image_file(key);
}

std::optional<int> Scheduler::slot_of_frame(const JobEntry& job, int frame) {
  const std::vector<int>& numbers = job.status.frames->numbers;
  const auto it = std::lower_bound(numbers.begin(), numbers.end(), frame);
  if (it == numbers.end() || *it != frame) return std::nullopt;
  return static_cast<int>(it - numbers.begin());
}

FrameRecord Scheduler::frame_info(const JobEntry& job, int slot) const {
  FrameRecord info;
  info.frame = job.status.frames->numbers[slot];
  info.tiles_total = job.tiles_per_frame;
  info.tiles_done = job.frame_done[slot];
  info.tiles_rendering = job.frame_rendering[slot];
  using protocol::FrameState;
  if (info.tiles_done == info.tiles_total) {
    info.state = FrameState::done;
  } else if (job.frame_spent[slot] > 0) {
    info.state = FrameState::failed;
    const int first = slot * job.tiles_per_frame;
    for (int index = first; index < first + job.tiles_per_frame; ++index) {
      const TileSlot& tile = job.tiles[index];
      if (tile.state == TileState::done || tile.attempts < config_.max_tile_attempts) continue;
      info.error = spent_tile_error(index - first, job.rect(index), tile);
      break;
    }
  } else if (info.tiles_rendering > 0 || info.tiles_done > 0) {
    info.state = FrameState::rendering;
  }
  return info;
}

std::optional<std::vector<FrameRecord>> Scheduler::frames(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  if (!job) return std::nullopt;
  std::vector<FrameRecord> frames;
  if (job->tiles_per_frame == 0) return frames;
  frames.reserve(job->frame_count());
  for (int slot = 0; slot < job->frame_count(); ++slot) frames.push_back(frame_info(*job, slot));
  return frames;
}

std::optional<FrameRecord> Scheduler::frame(const std::string& id, int frame) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  const std::optional<int> slot = job ? slot_of_frame(*job, frame) : std::nullopt;
  if (!slot || job->tiles_per_frame == 0) return std::nullopt;
  return frame_info(*job, *slot);
}

void Scheduler::wait_for_images() {
  // Completing writes hand their images over once durable.
  store_thread_.wait(store_thread_.last());
  images_.wait_for_images();
}

void Scheduler::image_write_failed(const std::string& key, const std::string& error) {
  std::lock_guard lock(mutex_);
  JobEntry* job = find_job(job_of_image(key));
  if (!job) return;
  const std::string why = (job->frame_count() == 1 ? "cannot write the image: "
                                                   : "cannot write the image " + key + ": ") +
                          error;
  StagedChange change;
  if (job->status.state == JobState::completed) {
    JobRecord& status = change.job(*job);
    status.state = JobState::failed;
    status.error = why;
  } else if (!is_finished(job->status.state)) {
    // A frame of an animation that renders on: it fails now rather than end "completed"
    // without that frame's image.
    stage_job_failure(change, *job, why);
  } else {
    return;
  }
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
