// How many bytes of request bodies the server holds at once. A body is read only once its
// announced length fits; until then it waits in the client's socket, and TCP holds the
// client back. Without this, a thousand workers uploading 768 KiB batches at once would
// have the coordinator hold 768 MiB of pixels waiting their turn for the scheduler.
#pragma once

#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <utility>

namespace tessera {

class BodyBudget {
 public:
  explicit BodyBudget(std::size_t limit) : limit_(limit) {}

  // Calls `go` once `bytes` fit: at once (on this thread) when they do now, else later from
  // whichever thread releases enough. A body larger than the whole budget goes when nothing
  // else is held. Waiters go in the order they came.
  void acquire(std::size_t bytes, std::function<void()> go);
  void release(std::size_t bytes);

  std::size_t limit() const { return limit_; }

 private:
  bool fits(std::size_t bytes) const { return held_ == 0 || held_ + bytes <= limit_; }

  const std::size_t limit_;
  std::mutex mutex_;
  std::size_t held_ = 0;
  std::deque<std::pair<std::size_t, std::function<void()>>> waiting_;
};

}  // namespace tessera
