// The one thread that touches the Store once the coordinator serves: the network's threads
// hand it their changes and go on, and hear back once the changes are durable.
//
// Writes queued while the thread is busy are committed together, in the order queued, in
// one transaction (group commit): a thousand workers' uploads cost one fsync-free WAL
// commit between them instead of one each, and nobody waits on the disk under a lock.
// Should that transaction fail, each of its writes is tried again alone, so that one
// change the store refuses (a full disk for one job's pixels) fails only itself. A write
// put off by a shortage that passes (StoreFault::transient: no descriptor left, a lock
// held by another process) is tried again until it passes, and refused for nothing.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "server/farm/store.hpp"

namespace tessera {

// A queued write's place in the queue: 1, 2, 3, ...; 0 is "nothing", durable at once.
using StoreTicket = std::uint64_t;

class StoreThread {
 public:
  using Work = std::function<void(Store&)>;
  // Told once a write is durable (`error` empty) or refused (`error` says why).
  using Done = std::function<void(const std::string& error)>;

  explicit StoreThread(Store& store);
  // Finishes every write and read queued, and their callbacks, before it returns.
  ~StoreThread();
  StoreThread(const StoreThread&) = delete;
  StoreThread& operator=(const StoreThread&) = delete;

  // Queues a write; it runs inside a transaction, and must throw to refuse.
  StoreTicket write(Work work);
  // The ticket of the last write queued: once it is durable, so is everything before it.
  StoreTicket last() const;
  // Calls `done` on the store thread once `ticket` is durable or refused, also when that
  // has happened already: never on the calling thread, which may hold a lock `done` takes.
  // The callbacks of one ticket run in the order they were given.
  void after(StoreTicket ticket, Done done);
  // Waits until `ticket` is durable or refused, and the callbacks given before have run;
  // returns the error, "" when it is durable. Never call it from the store thread.
  std::string wait(StoreTicket ticket);
  // Runs `work` on the store thread, after every write queued before it is durable: the
  // way any other thread reads the Store.
  void read(Work work);
  // read() and wait for it, from a thread that may wait on the disk (never the network's).
  void call(const Work& work);
  // Transactions committed so far, a group's and each write tried again alone: for tests
  // and logs.
  std::uint64_t transactions() const;

 private:
  struct Item {
    StoreTicket ticket = 0;  // 0 for a read
    Work work;
  };
  void run();
  // Writes `items`' writes in one transaction, or each alone should that fail; returns the
  // refused ones' errors by ticket.
  std::map<StoreTicket, std::string> commit(std::vector<Item>& items);
  // Writes them in one transaction, again and again while the store puts them off for a
  // passing shortage; the error that refused them, if any.
  std::optional<std::string> write_together(std::vector<Item>& items, bool alone);
  // Waits before the next try after `error`; false once a stopping thread should give up.
  bool wait_out(const std::exception& error, int attempt);

  Store& store_;
  mutable std::mutex mutex_;
  std::condition_variable queued_;
  std::deque<Item> queue_;
  StoreTicket last_ = 0;         // the last ticket given out
  StoreTicket finished_at_ = 0;  // every ticket up to this one is durable or refused, told
  std::multimap<StoreTicket, Done> waiting_;
  // The errors of the latest refused tickets, for callbacks given after the fact.
  std::map<StoreTicket, std::string> refused_;
  std::atomic<std::uint64_t> transactions_{0};  // see transactions()
  bool stopping_ = false;
  std::thread thread_;  // last: it starts once everything else exists
};

}  // namespace tessera
