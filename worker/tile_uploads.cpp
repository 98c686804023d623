#include "worker/tile_uploads.hpp"

#include <algorithm>

namespace tessera {

TileUploads::TileUploads(Send send, std::chrono::milliseconds gather, std::size_t max_group_tiles,
                         std::size_t max_group_bytes, int senders)
    : send_(std::move(send)),
      gather_(gather),
      max_group_tiles_(std::max<std::size_t>(max_group_tiles, 1)),
      max_group_bytes_(max_group_bytes) {
  for (int sender = 0; sender < std::max(senders, 1); ++sender)
    threads_.emplace_back([this, sender] { run(sender); });
}

TileUploads::~TileUploads() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  for (std::thread& thread : threads_) thread.join();
}

void TileUploads::set_limits(std::size_t max_group_tiles, std::size_t max_group_bytes) {
  {
    std::lock_guard lock(mutex_);
    max_group_tiles_ = std::max<std::size_t>(max_group_tiles, 1);
    max_group_bytes_ = max_group_bytes;
  }
  changed_.notify_all();
}

bool TileUploads::group_full() const {
  return ready_.size() >= max_group_tiles_ || ready_bytes_ >= max_group_bytes_;
}

void TileUploads::push(FinishedTile tile) {
  bool wake = false;
  {
    std::lock_guard lock(mutex_);
    const bool first = ready_.empty();
    ready_bytes_ += tile.pixels.size() * sizeof(float);
    ready_.push_back(std::move(tile));
    // The thread waits for a group's first tile, then for the group to fill (or its
    // gathering time to pass): only those wake it. Woken for every tile, it cost two
    // context switches and a system call per tile, a fifth of a worker's time at 8-pixel
    // tiles on a virtual machine.
    wake = first || prompt_ || flushing_ || group_full();
  }
  if (wake) changed_.notify_all();
}

bool TileUploads::flush() {
  std::unique_lock lock(mutex_);
  flushing_ = true;
  changed_.notify_all();
  changed_.wait(lock, [&] { return ready_.empty() && sending_ == 0; });
  flushing_ = false;
  prompt_ = false;
  return !refused_.exchange(false);
}

void TileUploads::send_promptly() {
  {
    std::lock_guard lock(mutex_);
    prompt_ = true;
  }
  changed_.notify_all();
}

std::vector<FinishedTile> TileUploads::take_group() {
  // Whole tiles up to both limits, and always at least one. What is left over waits for
  // the next group: tiles pile up while a group is on its way, or when they are small.
  std::size_t count = 0;
  std::size_t bytes = 0;
  while (count < ready_.size() && count < max_group_tiles_ &&
         (count == 0 || bytes + ready_[count].pixels.size() * sizeof(float) <= max_group_bytes_))
    bytes += ready_[count++].pixels.size() * sizeof(float);
  std::vector<FinishedTile> group(
      std::make_move_iterator(ready_.begin()),
      std::make_move_iterator(ready_.begin() + static_cast<long>(count)));
  ready_.erase(ready_.begin(), ready_.begin() + static_cast<long>(count));
  ready_bytes_ -= bytes;
  return group;
}

void TileUploads::run(int sender) {
  std::unique_lock lock(mutex_);
  while (true) {
    changed_.wait(lock, [&] { return stopping_ || !ready_.empty(); });
    if (ready_.empty()) return;  // stopping with nothing left to send
    changed_.wait_for(lock, gather_,
                      [&] { return stopping_ || flushing_ || prompt_ || group_full(); });
    if (ready_.empty()) continue;  // another sender took them meanwhile
    std::vector<FinishedTile> group = take_group();
    ++sending_;
    const bool dropped = refused_;
    lock.unlock();
    const bool sent = dropped || send_(sender, group);
    lock.lock();
    if (!sent) refused_ = true;
    --sending_;
    changed_.notify_all();
  }
}

}  // namespace tessera
