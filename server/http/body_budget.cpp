#include "server/http/body_budget.hpp"

#include <vector>

namespace tessera {

void BodyBudget::acquire(std::size_t bytes, std::function<void()> go) {
  {
    std::lock_guard lock(mutex_);
    if (!waiting_.empty() || !fits(bytes)) {
      waiting_.emplace_back(bytes, std::move(go));
      return;
    }
    held_ += bytes;
  }
  go();
}

void BodyBudget::release(std::size_t bytes) {
  std::vector<std::function<void()>> ready;
  {
    std::lock_guard lock(mutex_);
    held_ -= bytes;
    while (!waiting_.empty() && fits(waiting_.front().first)) {
      held_ += waiting_.front().first;
      ready.push_back(std::move(waiting_.front().second));
      waiting_.pop_front();
    }
  }
  // Outside the lock: a waiter may release at once (a body that failed to read).
  for (auto& go : ready) go();
}

}  // namespace tessera
