#include "worker/batch_tiles.hpp"

#include <algorithm>

namespace tessera {

BatchTiles::BatchTiles(std::vector<ClaimedTile> tiles, LeastLeft least_left, int last_count,
                       Extend extend)
    : least_left_(std::move(least_left)),
      last_batch_(tiles.size()),
      last_count_(last_count),
      extend_(std::move(extend)),
      tiles_(std::move(tiles)) {
  std::lock_guard lock(mutex_);
  consider_asking();
}

BatchTiles::~BatchTiles() { finish(); }

void BatchTiles::finish() {
  close();
  // asker_ is only started under the lock by a take(), and no take() is running now.
  if (asker_.joinable()) asker_.join();
}

void BatchTiles::consider_asking() {
  if (asking_ || final_ || closed_) return;
  const std::size_t when_left = std::max<std::size_t>(last_batch_ / 4, std::max(least_left_(), 0));
  if (tiles_.size() - next_ > when_left) return;
  // The last answer's thread has nothing left to do once it has cleared asking_.
  if (asker_.joinable()) asker_.join();
  asking_ = true;
  asker_ = std::thread([this] { ask(); });
}

void BatchTiles::ask() {
  std::optional<std::vector<ClaimedTile>> added = extend_();
  std::lock_guard lock(mutex_);
  asking_ = false;
  if (!added || added->empty()) {
    final_ = true;
  } else if (closed_) {
    // Leased to this worker all the same: counted, so that they are given back.
    tiles_.insert(tiles_.end(), added->begin(), added->end());
    final_ = true;
  } else {
    last_batch_ = added->size();
    tiles_.insert(tiles_.end(), added->begin(), added->end());
  }
  answered_.notify_all();
}

std::optional<BatchTiles::Taken> BatchTiles::take() {
  std::unique_lock lock(mutex_);
  answered_.wait(lock, [&] { return closed_ || next_ < tiles_.size() || final_ || !asking_; });
  if (closed_ || next_ == tiles_.size()) return std::nullopt;
  Taken taken{tiles_[next_++], false};
  const std::size_t left = tiles_.size() - next_;
  consider_asking();
  taken.among_last = final_ && left < static_cast<std::size_t>(last_count_);
  return taken;
}

void BatchTiles::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  answered_.notify_all();
}

int BatchTiles::count() const {
  std::lock_guard lock(mutex_);
  return static_cast<int>(tiles_.size());
}

bool BatchTiles::growing() const {
  std::lock_guard lock(mutex_);
  return !final_ && !closed_;
}

}  // namespace tessera
