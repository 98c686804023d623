// Long-polled requests: a worker asking for work when there is none, or a client waiting
// for its job to finish, is parked here until what it waits for may have happened
// (notify()) or its wait runs out. Nothing polls on a timer.
#pragma once

#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <atomic>
#include <chrono>
#include <functional>
#include <list>
#include <memory>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>

namespace tessera {

class LongPolls {
 public:
  explicit LongPolls(boost::asio::io_context& io);

  // Runs `attempt` now and, while it returns false, again after each notify() until
  // `wait` has passed; then calls `on_timeout`. Exactly one of a true attempt or
  // on_timeout ends each wait.
  void wait(std::chrono::milliseconds wait, std::function<bool()> attempt,
            std::function<void()> on_timeout);

  // Work may be available: wakes every parked claim. Safe from any thread.
  void notify();

  // Server shutdown: ends every parked claim with on_timeout, and every later wait at once,
  // so that workers see their stop signal instead of waiting out a long poll.
  void close();

 private:
  struct Waiter;
  void finish(const std::shared_ptr<Waiter>& waiter, bool claimed);

  boost::asio::strand<boost::asio::io_context::executor_type> strand_;
  std::list<std::shared_ptr<Waiter>> waiters_;  // touched on strand_ only
  std::atomic<bool> closed_{false};
};

}  // namespace tessera
