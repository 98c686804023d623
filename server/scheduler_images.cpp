// A job's image: its canvas, pasted together as its tiles become durable, the image of any
// job on request, and the image thread that makes canvases and writes finished images.
#include <sys/resource.h>
#include <unistd.h>

#include <stdexcept>

#include "server/scheduler.hpp"
#include "server/scheduler_entries.hpp"

namespace tessera {

void Scheduler::assemble(const std::string& id,
                         std::function<void(std::shared_ptr<const Image>)> then) const {
  {
    std::lock_guard lock(mutex_);
    const JobEntry* job = find_job(id);
    if (!job) return then(nullptr);
    // Only a finished job's canvas is safe to share: a running one still takes tiles.
    std::shared_ptr<const Image> image;
    if (job->canvas && is_finished(job->status.state)) image = job->canvas;
    if (job->canvas && !image) image = std::make_shared<const Image>(*job->canvas);
    if (image) return then(std::move(image));
  }
  // From the store, after every tile accepted so far is durable.
  store_thread_.read([this, id, then = std::move(then)](Store&) {
    std::shared_ptr<const Image> image;
    {
      std::lock_guard lock(mutex_);
      if (const JobEntry* job = find_job(id))
        image = std::make_shared<const Image>(assemble_locked(*job));
    }
    then(std::move(image));
  });
}

std::optional<std::filesystem::path> Scheduler::image_file(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const JobEntry* job = find_job(id);
  // The file appears whole (it is written beside its place and renamed), so once it is
  // there it can be sent.
  if (!job || job->status.state != JobState::completed || !images_.has(id)) return std::nullopt;
  return images_.path(id);
}

void Scheduler::make_canvas(const std::string& id, int width, int height,
                            std::unique_lock<std::mutex>& lock) {
  lock.unlock();
  auto canvas = std::make_shared<Image>(width, height);
  lock.lock();
  store_thread_.read(
      [this, id, canvas = std::move(canvas)](Store&) { install_canvas(id, canvas); });
}

void Scheduler::install_canvas(const std::string& id, const std::shared_ptr<Image>& canvas) {
  std::lock_guard lock(mutex_);
  JobEntry* job = find_job(id);  // it may have been removed meanwhile
  if (!job) return;
  job->canvas_coming = false;
  images_changed_.notify_all();  // the image thread may wait for it
  // A failed or canceled job's image comes from the store; a completed one's canvas is
  // taken by the image thread, which waited for it.
  if (job->status.state == JobState::failed || job->status.state == JobState::canceled) return;
  // On the store thread: every result durable so far is in the store, and every later one
  // is pasted by note_stored().
  paste_stored(*canvas, *job);
  job->canvas = canvas;
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
  // Every stored result is a tile accepted once: a tile delivered again is refused, and
  // what start-up found unusable it deleted before anything was assembled.
  store_.for_each_tile_pixels(job.status.id, floats_of,
                              [&](int index, std::span<const float> pixels) {
                                image.paste(job.tiles[index].rect, pixels);
                              });
}

void Scheduler::wait_for_images() {
  // Completing writes queue their images once durable.
  store_thread_.wait(store_thread_.last());
  std::unique_lock lock(mutex_);
  images_changed_.wait(lock, [&] {
    return images_to_write_.empty() && canvases_to_make_.empty() && !writing_image_;
  });
}

void Scheduler::write_images() {
  // Below the threads that answer requests and render: an image file is for later.
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);
  std::unique_lock lock(mutex_);
  while (true) {
    images_changed_.wait(
        lock, [&] { return stopping_ || !images_to_write_.empty() || !canvases_to_make_.empty(); });
    // Canvases first: an image to write may wait for its job's canvas.
    if (!canvases_to_make_.empty()) {
      const auto [id, width, height] = std::move(canvases_to_make_.front());
      canvases_to_make_.pop_front();
      writing_image_ = true;
      make_canvas(id, width, height, lock);
      writing_image_ = false;
      images_changed_.notify_all();
      continue;
    }
    if (images_to_write_.empty()) return;  // stopping, and nothing is left to write
    const std::string id = std::move(images_to_write_.front());
    images_to_write_.pop_front();
    writing_image_ = true;
    write_image(id, lock);
    writing_image_ = false;
    images_changed_.notify_all();
  }
}

void Scheduler::write_image(const std::string& id, std::unique_lock<std::mutex>& lock) {
  // A canvas on its way is waited for, rather than assembling a second one from the store.
  const JobEntry* job = find_job(id);
  while (job && job->canvas_coming) {
    images_changed_.wait(lock);
    job = find_job(id);
  }
  if (!job || job->status.state != JobState::completed) return;
  std::string error;
  try {
    // A completed job's canvas changes no more, so it can be read outside the lock.
    std::shared_ptr<const Image> image = job->canvas;
    lock.unlock();
    if (!image)
      store_thread_.call([&](Store&) {
        std::lock_guard relock(mutex_);
        if (const JobEntry* still = find_job(id))
          image = std::make_shared<const Image>(assemble_locked(*still));
      });
    // Encoding takes a while and touches no shared state: workers and clients go on.
    if (image) images_.write(id, *image);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!lock.owns_lock()) lock.lock();
  JobEntry* still = find_job(id);
  if (!still) {
    images_.remove(id);  // removed while it was being written
    return;
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

}  // namespace tessera
