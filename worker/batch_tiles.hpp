// The tiles of the lease a worker is rendering. Its rendering threads take them one by one,
// in the lease's order; before they run out, more of the same job are asked for on a
// thread of its own (POST /v1/leases/{id}/extend), so that the threads go on from one
// batch to the next without waiting on the last uploads and a claim in between.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "common/image/image.hpp"

namespace tessera {

struct ClaimedTile {
  int index = 0;  // the tile's index in its job
  TileRect rect;
};

class BatchTiles {
 public:
  // More tiles for the lease: those added (none when the coordinator has none to add), or
  // nothing when it could not say (the lease was lost, the coordinator is unreachable).
  using Extend = std::function<std::optional<std::vector<ClaimedTile>>()>;

  // How many tiles left to take are few enough to ask for more: read before each ask.
  using LeastLeft = std::function<int()>;

  // Asks `extend` once the tiles left to take fall to a quarter of the last batch (the
  // lease's own tiles, then each answer's), or to `least_left()` if more, and again after
  // each answer that added some, until one adds none. The last `last_count` tiles, once
  // none will be added, are taken with `among_last` set.
  BatchTiles(std::vector<ClaimedTile> tiles, LeastLeft least_left, int last_count, Extend extend);
  BatchTiles(std::vector<ClaimedTile> tiles, int least_left, int last_count, Extend extend)
      : BatchTiles(
            std::move(tiles), [least_left] { return least_left; }, last_count, std::move(extend)) {}
  // finish()es.
  ~BatchTiles();
  BatchTiles(const BatchTiles&) = delete;
  BatchTiles& operator=(const BatchTiles&) = delete;

  struct Taken {
    ClaimedTile tile;
    bool among_last;  // no tile will be added, and at most last_count are left after it
  };
  // The next tile, or nothing once every tile is taken and none will be added. While an
  // extension is on its way and no tile is left, waits for its answer.
  std::optional<Taken> take();
  // No tile is handed out from now on (a tile failed, the lease was lost, the worker
  // stops), and none is asked for. Safe from any thread.
  void close();
  // close(), then waits for an extension on its way: what it added is the lease's too.
  // For the owner, once the rendering threads are done.
  void finish();
  // Every tile the lease has held so far, taken or not: all of them after finish().
  int count() const;
  // False once no tile will be added (an answer added none, or close()).
  bool growing() const;

 private:
  // Starts asking when it is time to; called with mutex_ held.
  void consider_asking();
  void ask();  // on asker_

  const LeastLeft least_left_;
  std::size_t last_batch_;  // tiles in the lease, then in the last answer
  const int last_count_;
  Extend extend_;
  mutable std::mutex mutex_;
  std::condition_variable answered_;
  std::vector<ClaimedTile> tiles_;
  std::size_t next_ = 0;
  bool asking_ = false;  // an extension is on its way
  bool final_ = false;   // no tile will be added
  bool closed_ = false;
  std::thread asker_;
};

}  // namespace tessera
