#include "worker/tile_uploader.hpp"

namespace tessera {

TileUploader::TileUploader(std::function<void(const FinishedTile&)> upload)
    : upload_(std::move(upload)), thread_([this] { run(); }) {}

TileUploader::~TileUploader() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void TileUploader::push(FinishedTile tile) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return queue_.empty(); });
  queue_.push_back(std::move(tile));
  changed_.notify_all();
}

void TileUploader::drain() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
}

void TileUploader::run() {
  std::unique_lock lock(mutex_);
  while (true) {
    changed_.wait(lock, [&] { return !queue_.empty() || stopping_; });
    if (queue_.empty()) return;  // stopping, and everything is sent
    FinishedTile tile = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    changed_.notify_all();
    lock.unlock();
    upload_(tile);
    lock.lock();
    busy_ = false;
    changed_.notify_all();
  }
}

}  // namespace tessera
