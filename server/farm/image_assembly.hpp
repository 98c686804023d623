// The images of the jobs, each named by its key (a still job's id, or a frame's,
// image_key()): each running image's canvas, into which its tiles are pasted as
// they become durable, the image of any job on request, and the image thread that makes
// canvases and writes each completed job's image file (ImageFiles) off the path of any
// request. The Scheduler tells it what happens to a job; it never calls the Scheduler
// back but through `write_failed`.
#pragma once

#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/image/image.hpp"
#include "server/farm/image_files.hpp"
#include "server/farm/store_thread.hpp"

namespace tessera {

// What an image is made of: a still job's, or one frame's of an animation. Fixed at
// submit. Every frame of a job is cut alike, so its frames share one list of rectangles;
// the job numbers its tiles frame after frame, this frame's from `first_tile` on.
struct Frame {
  int width = 0;
  int height = 0;
  std::shared_ptr<const std::vector<TileRect>> tiles;  // one frame's, by index in the frame
  std::string job_id;  // whose results (and pixel file) hold its tiles
  int first_tile = 0;  // the job's index of this frame's first tile
  int job_tiles = 0;   // the job's tiles, every frame's

  bool holds(int job_index) const {
    return job_index >= first_tile && job_index - first_tile < static_cast<int>(tiles->size());
  }
  const TileRect& rect(int job_index) const { return (*tiles)[job_index - first_tile]; }
};

class ImageAssembly {
 public:
  // Called on the image thread, unlocked, when a completed job's image cannot be written.
  using WriteFailed = std::function<void(const std::string& key, const std::string& error)>;

  ImageAssembly(const std::filesystem::path& data_dir, StoreThread& store,
                WriteFailed write_failed);
  // Writes the images still queued, then stops the image thread (stop()).
  ~ImageAssembly();
  // Writes the images still queued and stops the image thread; later calls do nothing.
  void stop();
  ImageAssembly(const ImageAssembly&) = delete;
  ImageAssembly& operator=(const ImageAssembly&) = delete;

  // Where a job's image comes from: its tiles as they arrive, its image file, the store.
  enum class Stage { rendering, completed, ended };
  // A job whose image may be asked for: at submit, or at start-up for every stored job
  // (a completed one without its image file is then also completed()).
  void add(const std::string& key, std::shared_ptr<const Frame> frame,
           Stage stage = Stage::rendering);
  // On the store thread, once these tiles of the job are durable: pasted into its canvas,
  // or, without one, the canvas is asked for (not for a job's `last` tiles: its image is
  // then written from the store).
  void stored(const std::string& key,
              const std::vector<std::pair<int, std::span<const float>>>& tiles, bool last);
  // The job's completion is durable: the image thread writes its image file.
  void completed(const std::string& key);
  // The job failed or was canceled: its image comes from the store from now on.
  void ended(const std::string& key);
  // The ended job renders again (a failed job retried): its tiles go to a canvas again.
  void resumed(const std::string& key);
  // The job's removal is durable: its image file goes too.
  void removed(const std::string& key);

  // The job's image as assembled so far, handed to `then`: on this thread from its canvas,
  // or on the store thread from the store; null for a job it does not know. `finished`:
  // the scheduler has the job completed, which it may tell others (an event, a long poll)
  // before the callbacks of the same write have pasted its last tiles and marked it
  // completed here; the image is then taken on the store thread, after those callbacks.
  void assemble(const std::string& key, std::function<void(std::shared_ptr<const Image>)> then,
                bool finished = false) const;
  // The image file of a completed job, once written.
  std::optional<std::filesystem::path> image_file(const std::string& key) const;
  bool has_file(const std::string& key) const { return files_.has(key); }
  // Deletes the image files of jobs that are not completed ones (start-up).
  void prune_files(const std::function<bool(const std::string& key)>& completed) const;
  // Waits until every canvas asked for is made and every image queued is written.
  void wait_for_images();

 private:
  struct Job {
    std::shared_ptr<const Frame> frame;
    std::shared_ptr<Image> canvas;  // from the first durable tiles until the file is written
    bool canvas_coming = false;     // asked of the image thread, not yet in place
    bool completed = false;
    bool ended = false;  // failed or canceled
  };
  // Pastes every stored tile of the job into `image`; on the store thread only.
  static void paste_stored(Store& store, Image& image, const Frame& frame);
  void run();
  // The image thread zeroes a canvas (3 GiB for a 16384x16384 frame takes a second or more,
  // which no request and no commit should wait out); the store thread then pastes what is
  // stored into it and puts it in place, so that no durable tile is missed.
  void make_canvas(const std::string& key, std::unique_lock<std::mutex>& lock);
  void install_canvas(Store& store, const std::string& key, std::shared_ptr<Image> canvas);
  void write_image(const std::string& key, std::unique_lock<std::mutex>& lock);
  // Whether `error` is a shortage that passes (no descriptor left), which fails nothing.
  bool passing_shortage(const std::exception& error) const;
  // Waits before the next try; false once the image is no longer wanted (its job removed,
  // the coordinator stopping).
  bool wait_out_shortage(const std::string& key, const std::exception& error, int attempt);

  ImageFiles files_;
  StoreThread& store_;
  WriteFailed write_failed_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::unordered_map<std::string, Job> jobs_;
  std::deque<std::string> canvases_to_make_;
  std::deque<std::string> images_to_write_;  // oldest first
  bool busy_ = false;                        // the image thread is at work on one of them
  bool stopping_ = false;
  std::thread thread_;  // last: it starts once everything else exists
};

}  // namespace tessera
