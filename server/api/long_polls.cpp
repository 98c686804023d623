#include "server/api/long_polls.hpp"

#include <boost/asio/post.hpp>

namespace tessera {

struct LongPolls::Waiter {
  explicit Waiter(boost::asio::strand<boost::asio::io_context::executor_type>& strand)
      : timer(strand) {}
  boost::asio::steady_timer timer;
  std::function<bool()> attempt;
  std::function<void()> on_timeout;
  std::list<std::shared_ptr<Waiter>>::iterator position;
  bool done = false;
};

LongPolls::LongPolls(boost::asio::io_context& io) : strand_(boost::asio::make_strand(io)) {}

void LongPolls::wait(std::chrono::milliseconds wait, std::function<bool()> attempt,
                     std::function<void()> on_timeout) {
  if (attempt()) return;
  if (wait.count() <= 0 || closed_) {
    on_timeout();
    return;
  }
  auto waiter = std::make_shared<Waiter>(strand_);
  waiter->attempt = std::move(attempt);
  waiter->on_timeout = std::move(on_timeout);
  waiter->timer.expires_after(wait);
  boost::asio::post(strand_, [this, waiter] {
    if (closed_) {
      waiter->on_timeout();
      return;
    }
    waiters_.push_front(waiter);
    waiter->position = waiters_.begin();
    // Work may have arrived between the first attempt and parking.
    if (waiter->attempt()) {
      finish(waiter, true);
      return;
    }
    waiter->timer.async_wait([this, waiter](const boost::system::error_code& ec) {
      if (ec || waiter->done) return;  // canceled by finish()
      finish(waiter, waiter->attempt());
    });
  });
}

void LongPolls::finish(const std::shared_ptr<Waiter>& waiter, bool claimed) {
  if (waiter->done) return;
  waiter->done = true;
  waiters_.erase(waiter->position);
  waiter->timer.cancel();
  if (!claimed) waiter->on_timeout();
}

void LongPolls::notify() {
  boost::asio::post(strand_, [this] {
    // Copy: finish() removes from the list while we walk it.
    const std::list<std::shared_ptr<Waiter>> parked = waiters_;
    for (const auto& waiter : parked)
      if (!waiter->done && waiter->attempt()) finish(waiter, true);
  });
}

void LongPolls::close() {
  closed_ = true;
  boost::asio::post(strand_, [this] {
    const std::list<std::shared_ptr<Waiter>> parked = waiters_;
    for (const auto& waiter : parked) finish(waiter, false);
  });
}

}  // namespace tessera
