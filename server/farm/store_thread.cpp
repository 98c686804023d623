#include "server/farm/store_thread.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <future>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "server/farm/store_error.hpp"

namespace tessera {
namespace {

// Enough for any callback given right after its write was queued; older errors are
// forgotten so that a long run of refusals (a disk that stays full) costs bounded memory.
constexpr std::size_t kRefusalsKept = 4096;
// Tries of a write the store put off for a passing shortage, once the thread is stopping
// (about 5 s in all); before that it tries for as long as the shortage lasts.
constexpr int kAttemptsWhenStopping = 10;

}  // namespace

StoreThread::StoreThread(Store& store) : store_(store), thread_([this] { run(); }) {}

StoreThread::~StoreThread() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  queued_.notify_all();
  thread_.join();
}

StoreTicket StoreThread::write(Work work) {
  std::lock_guard lock(mutex_);
  queue_.push_back({++last_, std::move(work)});
  queued_.notify_one();
  return last_;
}

StoreTicket StoreThread::last() const {
  std::lock_guard lock(mutex_);
  return last_;
}

void StoreThread::after(StoreTicket ticket, Done done) {
  std::lock_guard lock(mutex_);
  if (ticket > finished_at_) {
    waiting_.emplace(ticket, std::move(done));
    return;
  }
  // Told already: told again on the store thread, never here, since the caller may hold a
  // lock that the callback takes.
  const auto it = refused_.find(ticket);
  queue_.push_back({0, [error = it == refused_.end() ? std::string() : it->second,
                        done = std::move(done)](Store&) { done(error); }});
  queued_.notify_one();
}

std::string StoreThread::wait(StoreTicket ticket) {
  // As a callback of its own, so that it returns after every callback given before it.
  std::promise<std::string> told;
  after(ticket, [&](const std::string& error) { told.set_value(error); });
  return told.get_future().get();
}

void StoreThread::read(Work work) {
  std::lock_guard lock(mutex_);
  queue_.push_back({0, std::move(work)});
  queued_.notify_one();
}

void StoreThread::call(const Work& work) {
  std::promise<void> finished;
  read([&](Store& store) {
    try {
      work(store);
      finished.set_value();
    } catch (...) {
      finished.set_exception(std::current_exception());
    }
  });
  finished.get_future().get();
}

std::uint64_t StoreThread::transactions() const { return transactions_.load(); }

void StoreThread::run() {
  std::unique_lock lock(mutex_);
  while (true) {
    queued_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, and everything queued is done
    std::vector<Item> items(std::make_move_iterator(queue_.begin()),
                            std::make_move_iterator(queue_.end()));
    queue_.clear();
    lock.unlock();

    std::map<StoreTicket, std::string> refused = commit(items);
    // Reads after the writes queued with them: a read sees at least what was queued before.
    for (Item& item : items) {
      if (item.ticket != 0) continue;
      try {
        item.work(store_);
      } catch (const std::exception& e) {
        spdlog::error("reading the store: {}", e.what());
      }
    }
    StoreTicket newest = 0;
    for (const Item& item : items) newest = std::max(newest, item.ticket);
    // What the work held (a submitted scene's text can be tens of megabytes) is freed
    // before the callbacks, which may then give that memory back to the system.
    items.clear();

    lock.lock();
    for (const auto& [ticket, error] : refused) refused_[ticket] = error;
    while (refused_.size() > kRefusalsKept) refused_.erase(refused_.begin());
    if (newest == 0) continue;
    // Tickets are told in order, each ticket's callbacks in the order given. A callback
    // may queue more work, or give more callbacks (for later tickets); it runs unlocked.
    while (!waiting_.empty() && waiting_.begin()->first <= newest) {
      auto node = waiting_.extract(waiting_.begin());
      const auto it = refused.find(node.key());
      const std::string error = it == refused.end() ? std::string() : it->second;
      lock.unlock();
      try {
        node.mapped()(error);
      } catch (const std::exception& e) {
        spdlog::error("after a store write: {}", e.what());
      }
      lock.lock();
    }
    finished_at_ = newest;
  }
}

bool StoreThread::wait_out(const std::exception& error, int attempt) {
  {
    // A coordinator that is stopping waits a few seconds, then refuses what it cannot store.
    std::lock_guard lock(mutex_);
    if (stopping_ && attempt >= kAttemptsWhenStopping) return false;
  }
  if (attempt % 60 == 0)
    spdlog::warn("store: {}; writing again in a moment, nothing fails for it", error.what());
  // 10 ms, doubling to about a second: a shortage of descriptors ends as connections
  // close, a lock another process holds when it lets go. Meanwhile nothing later commits
  // either, since writes are stored in the order they were queued.
  std::this_thread::sleep_for(std::chrono::milliseconds(10) * (1 << std::min(attempt, 7)));
  return true;
}

std::optional<std::string> StoreThread::write_together(std::vector<Item>& items, bool alone) {
  for (int attempt = 0;; ++attempt) {
    try {
      store_.atomically([&] {
        for (Item& item : items)
          if (item.ticket != 0) item.work(store_);
      });
      ++transactions_;
      return std::nullopt;
    } catch (const std::exception& e) {
      if (fault_of(e) == StoreFault::transient && wait_out(e, attempt)) continue;
      if (!alone) spdlog::debug("store: a group of writes failed ({}); each alone", e.what());
      return std::string(e.what());
    } catch (...) {
      return std::string("unknown error");
    }
  }
}

std::map<StoreTicket, std::string> StoreThread::commit(std::vector<Item>& items) {
  std::map<StoreTicket, std::string> refused;
  std::size_t writes = 0;
  for (const Item& item : items) writes += item.ticket != 0;
  if (writes == 0) return refused;
  const std::optional<std::string> error = write_together(items, writes == 1);
  if (!error) return refused;
  if (writes == 1) {
    for (const Item& item : items)
      if (item.ticket != 0) refused[item.ticket] = *error;
    return refused;
  }
  // One of them spoiled the group: each alone, so that only what the store refuses fails.
  for (Item& item : items) {
    if (item.ticket == 0) continue;
    std::vector<Item> one;
    one.push_back({item.ticket, std::move(item.work)});
    if (const std::optional<std::string> alone = write_together(one, true))
      refused[item.ticket] = *alone;
  }
  return refused;
}

}  // namespace tessera
