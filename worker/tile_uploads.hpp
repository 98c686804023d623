// Finished tiles travel to the coordinator from threads of their own, so that rendering
// goes on while they are on the way. Tiles that finish close together share one request:
// the coordinator then pays for one request and one transaction per group, not per tile.
// Several groups may be on their way at once, one per sender, each sender with a
// connection of its own: one group waits for its answer while the next is sent, so that
// a worker of many threads and small tiles is not held to one round trip per group.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace tessera {

struct FinishedTile {
  int index = 0;  // the tile's index in its job
  std::vector<float> pixels;
  std::uint64_t rays = 0;
  std::uint64_t render_us = 0;  // how long it took its thread
};

class TileUploads {
 public:
  // Sends one group of the current lease's tiles, as sender `sender` (0 to senders - 1; no
  // two calls share one at a time); returns false when the coordinator refused it (the
  // lease is lost), after which the lease's later tiles are dropped.
  using Send = std::function<bool(int sender, const std::vector<FinishedTile>&)>;

  // A group is sent once `gather` has passed since its first tile was ready, when it
  // reaches `max_group_tiles` tiles or `max_group_bytes` of pixels, or on flush(). A group
  // never holds more than either, except that a tile larger than `max_group_bytes` goes
  // alone (the coordinator takes any one tile: ProtocolLimits::max_result_bytes).
  TileUploads(Send send, std::chrono::milliseconds gather, std::size_t max_group_tiles,
              std::size_t max_group_bytes, int senders = 1);
  ~TileUploads();
  TileUploads(const TileUploads&) = delete;
  TileUploads& operator=(const TileUploads&) = delete;

  // New limits for the groups from now on, as a coordinator stated at registration.
  void set_limits(std::size_t max_group_tiles, std::size_t max_group_bytes);

  void push(FinishedTile tile);
  // Sends what is left and waits until every pushed tile has been sent or dropped. Returns
  // false when the coordinator refused a group since the last flush; then clears that.
  bool flush();
  // Ends the gathering until the next flush(): what is ready goes now, and each tile pushed
  // after it goes as soon as the thread is free. For the last tiles of a lease, which have
  // no later tiles to share a group with, so that flush() waits for little more than the
  // very last one.
  void send_promptly();
  // True once the coordinator refused a group of the current lease.
  bool refused() const { return refused_; }

 private:
  void run(int sender);
  std::vector<FinishedTile> take_group();
  bool group_full() const;  // with mutex_ held

  Send send_;
  std::chrono::milliseconds gather_;
  std::size_t max_group_tiles_;
  std::size_t max_group_bytes_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<FinishedTile> ready_;
  std::size_t ready_bytes_ = 0;
  bool flushing_ = false;
  bool prompt_ = false;
  int sending_ = 0;  // groups on their way
  bool stopping_ = false;
  std::atomic<bool> refused_{false};
  std::vector<std::thread> threads_;
};

}  // namespace tessera
