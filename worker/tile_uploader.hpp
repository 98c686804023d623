// Sends finished tiles to the coordinator from a thread of its own, so that the rendering
// threads go on with the next tile while the last one is on the wire.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace tessera {

struct FinishedTile {
  std::string lease_id;
  std::vector<float> pixels;
  std::uint64_t rays = 0;
};

class TileUploader {
 public:
  // `upload` sends one tile (it retries on its own while the coordinator is unreachable).
  explicit TileUploader(std::function<void(const FinishedTile&)> upload);
  // Sends what is queued, then stops.
  ~TileUploader();
  TileUploader(const TileUploader&) = delete;
  TileUploader& operator=(const TileUploader&) = delete;

  // Queues a tile; waits while one is already waiting, so the worker never runs more than
  // one tile ahead of its uploads.
  void push(FinishedTile tile);
  // Waits until every queued tile has been sent.
  void drain();

 private:
  void run();

  std::function<void(const FinishedTile&)> upload_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<FinishedTile> queue_;
  bool busy_ = false;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace tessera
