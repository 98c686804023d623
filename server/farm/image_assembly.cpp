#include "server/farm/image_assembly.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "server/farm/store_error.hpp"

namespace tessera {

ImageAssembly::ImageAssembly(const std::filesystem::path& data_dir, StoreThread& store,
                             WriteFailed write_failed)
    : files_(data_dir),
      store_(store),
      write_failed_(std::move(write_failed)),
      thread_([this] { run(); }) {}

ImageAssembly::~ImageAssembly() { stop(); }

void ImageAssembly::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ImageAssembly::add(const std::string& key, std::shared_ptr<const Frame> frame, Stage stage) {
  std::lock_guard lock(mutex_);
  Job& job = jobs_[key];
  job.frame = std::move(frame);
  job.completed = stage == Stage::completed;
  job.ended = stage == Stage::ended;
}

void ImageAssembly::stored(const std::string& key,
                           const std::vector<std::pair<int, std::span<const float>>>& tiles,
                           bool last) {
  std::lock_guard lock(mutex_);
  const auto it = jobs_.find(key);
  if (it == jobs_.end()) return;
  Job& job = it->second;
  if (job.canvas) {
    for (const auto& [index, pixels] : tiles) job.canvas->paste(job.frame->rect(index), pixels);
  } else if (!job.canvas_coming && !last && !job.completed && !job.ended) {
    // The job's first tiles, or the first since a restart: these are only stored, and
    // the canvas, made next, starts from the store.
    job.canvas_coming = true;
    canvases_to_make_.push_back(key);
    changed_.notify_all();
  }
}

void ImageAssembly::completed(const std::string& key) {
  std::lock_guard lock(mutex_);
  const auto it = jobs_.find(key);
  if (it == jobs_.end()) return;
  it->second.completed = true;
  // Should the write fail or the process die, the tiles are stored and a restart writes
  // the image again.
  images_to_write_.push_back(key);
  changed_.notify_all();
}

void ImageAssembly::ended(const std::string& key) {
  std::lock_guard lock(mutex_);
  const auto it = jobs_.find(key);
  if (it == jobs_.end()) return;
  it->second.ended = true;
  it->second.completed = false;
  it->second.canvas.reset();
}

void ImageAssembly::resumed(const std::string& key) {
  std::lock_guard lock(mutex_);
  const auto it = jobs_.find(key);
  if (it != jobs_.end()) it->second.ended = false;
}

void ImageAssembly::removed(const std::string& key) {
  std::lock_guard lock(mutex_);
  jobs_.erase(key);
  // After the job's rows: a file left behind by a failure here is pruned on the next start,
  // while a row without its image would be a completed job that cannot be served. One
  // being written now is removed once written (write_image()).
  files_.remove(key);
}

void ImageAssembly::assemble(const std::string& key,
                             std::function<void(std::shared_ptr<const Image>)> then,
                             bool finished) const {
  if (finished) {
    // A read runs in a later round of the store thread than the callbacks of every write
    // durable now, so its canvas has every tile and its completion is known here.
    store_.read([this, key, then = std::move(then)](Store&) mutable {
      assemble(key, std::move(then), false);
    });
    return;
  }
  std::shared_ptr<const Frame> frame;
  {
    std::lock_guard lock(mutex_);
    const auto it = jobs_.find(key);
    if (it == jobs_.end()) return then(nullptr);
    const Job& job = it->second;
    // A completed job's canvas changes no more and can be shared; a running one's is copied.
    if (job.canvas && job.completed) return then(job.canvas);
    if (job.canvas) return then(std::make_shared<const Image>(*job.canvas));
    frame = job.frame;
  }
  // From the store, after every tile accepted so far is durable.
  store_.read([key, frame, then = std::move(then)](Store& store) {
    auto image = std::make_shared<Image>(frame->width, frame->height);
    paste_stored(store, *image, *frame);
    then(std::move(image));
  });
}

std::optional<std::filesystem::path> ImageAssembly::image_file(const std::string& key) const {
  std::lock_guard lock(mutex_);
  const auto it = jobs_.find(key);
  // The file appears whole (it is written beside its place and renamed), so once it is
  // there it can be sent.
  if (it == jobs_.end() || !it->second.completed || !files_.has(key)) return std::nullopt;
  return files_.path(key);
}

void ImageAssembly::prune_files(
    const std::function<bool(const std::string& key)>& completed) const {
  files_.prune(completed);
}

void ImageAssembly::wait_for_images() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock,
                [&] { return images_to_write_.empty() && canvases_to_make_.empty() && !busy_; });
}

void ImageAssembly::paste_stored(Store& store, Image& image, const Frame& frame) {
  const auto floats_of = [&](int index) -> std::size_t {
    if (index < 0 || index >= frame.job_tiles)
      throw std::runtime_error("job " + frame.job_id + ": stored pixels for unknown tile " +
                               std::to_string(index));
    // Every frame is cut alike: a tile of another frame is the size of this one's.
    return (*frame.tiles)[index % frame.tiles->size()].pixel_count() * 3;
  };
  // Every stored result is a tile accepted once: a tile delivered again is refused, and
  // what start-up found unusable it deleted before anything was assembled.
  store.for_each_tile_pixels(
      frame.job_id, floats_of,
      [&](int index, std::span<const float> pixels) { image.paste(frame.rect(index), pixels); },
      [&](int index) { return frame.holds(index); });
}

void ImageAssembly::run() {
  // Below the threads that answer requests and render: an image file is for later.
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);
  std::unique_lock lock(mutex_);
  while (true) {
    changed_.wait(
        lock, [&] { return stopping_ || !images_to_write_.empty() || !canvases_to_make_.empty(); });
    busy_ = true;
    // Canvases first: an image to write may wait for its job's canvas.
    if (!canvases_to_make_.empty()) {
      const std::string id = std::move(canvases_to_make_.front());
      canvases_to_make_.pop_front();
      make_canvas(id, lock);
    } else if (!images_to_write_.empty()) {
      const std::string id = std::move(images_to_write_.front());
      images_to_write_.pop_front();
      write_image(id, lock);
    } else {
      return;  // stopping, and nothing is left to do
    }
    busy_ = false;
    changed_.notify_all();
  }
}

void ImageAssembly::make_canvas(const std::string& key, std::unique_lock<std::mutex>& lock) {
  const auto it = jobs_.find(key);
  if (it == jobs_.end()) return;
  const std::shared_ptr<const Frame> frame = it->second.frame;
  lock.unlock();
  auto canvas = std::make_shared<Image>(frame->width, frame->height);
  store_.read([this, key, canvas = std::move(canvas)](Store& store) mutable {
    install_canvas(store, key, std::move(canvas));
  });
  lock.lock();
}

void ImageAssembly::install_canvas(Store& store, const std::string& key,
                                   std::shared_ptr<Image> canvas) {
  std::shared_ptr<const Frame> frame;
  {
    std::lock_guard lock(mutex_);
    const auto it = jobs_.find(key);  // it may have been removed meanwhile
    if (it == jobs_.end()) return;
    frame = it->second.frame;
  }
  // On the store thread, unlocked: every tile durable so far is in the store, and every
  // later one is pasted by stored(), which runs on this thread too.
  bool pasted = true;
  try {
    paste_stored(store, *canvas, *frame);
  } catch (const std::exception& e) {
    // No descriptor for the pixel file, say: the job goes on without a canvas, and its
    // image is assembled from the store once it is done (write_image).
    spdlog::warn("image {}: cannot read its stored tiles yet: {}", key, e.what());
    pasted = false;
  }
  std::lock_guard lock(mutex_);
  const auto it = jobs_.find(key);
  if (it == jobs_.end()) return;
  Job& job = it->second;
  job.canvas_coming = false;
  changed_.notify_all();  // the image thread may wait for it
  // A failed or canceled job's image comes from the store; a completed one's canvas is
  // taken by the image thread, which waited for it.
  if (!job.ended && pasted) job.canvas = std::move(canvas);
}

bool ImageAssembly::passing_shortage(const std::exception& error) const {
  if (fault_of(error) == StoreFault::transient) return true;
  // An image file's own write says only what OpenImageIO says: whether this process is
  // out of descriptors is asked of the system again.
  const int probe = ::open(files_.dir().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (probe >= 0) {
    ::close(probe);
    return false;
  }
  return fault_of_errno(errno) == StoreFault::transient;
}

bool ImageAssembly::wait_out_shortage(const std::string& key, const std::exception& error,
                                      int attempt) {
  if (attempt % 30 == 0)
    spdlog::warn("image {}: {}; writing it again in a moment, nothing fails for it", key,
                 error.what());
  std::unique_lock lock(mutex_);
  // 10 ms, doubling to about a second; a job removed meanwhile, or a coordinator that
  // stops, ends it (the next start writes the images of frames done that lack one).
  changed_.wait_for(lock, std::chrono::milliseconds(10) * (1 << std::min(attempt, 7)),
                    [&] { return stopping_ || !jobs_.contains(key); });
  return !stopping_ && jobs_.contains(key);
}

void ImageAssembly::write_image(const std::string& key, std::unique_lock<std::mutex>& lock) {
  // A canvas on its way is waited for, rather than assembling a second one from the store.
  auto it = jobs_.find(key);
  while (it != jobs_.end() && it->second.canvas_coming) {
    changed_.wait(lock);
    it = jobs_.find(key);
  }
  if (it == jobs_.end() || !it->second.completed) return;
  // A completed job's canvas changes no more, so it can be read unlocked.
  std::shared_ptr<const Image> image = it->second.canvas;
  const std::shared_ptr<const Frame> frame = it->second.frame;
  lock.unlock();
  std::string error;
  for (int attempt = 0;; ++attempt) {
    try {
      if (!image)
        store_.call([&](Store& store) {
          auto assembled = std::make_shared<Image>(frame->width, frame->height);
          paste_stored(store, *assembled, *frame);
          image = std::move(assembled);
        });
      // Encoding takes a while and touches no shared state: workers and clients go on.
      files_.write(key, *image);
      break;
    } catch (const std::exception& e) {
      // A shortage that passes (no descriptor left) fails no job: the image is written
      // once it has passed. Until then downloads assemble it from the store.
      if (!passing_shortage(e) || !wait_out_shortage(key, e, attempt)) {
        error = e.what();
        break;
      }
    }
  }
  lock.lock();
  it = jobs_.find(key);
  if (it == jobs_.end()) {
    files_.remove(key);  // removed while it was being written
    return;
  }
  it->second.canvas.reset();  // the file (or the store) serves it from now on
  if (error.empty() || !it->second.completed) return;
  // Every tile is stored, so a resubmission renders again; a "completed" job without an
  // image file would only fail later, when someone looks for it.
  spdlog::error("image {}: cannot write it: {}", key, error);
  lock.unlock();
  write_failed_(key, error);
  lock.lock();
}

}  // namespace tessera
