#include "server/api/submit_budget.hpp"

namespace tessera {

SubmitBudget::Hold::~Hold() {
  if (budget_) budget_->release(bytes_);
}

std::optional<SubmitBudget::Hold> SubmitBudget::try_hold(std::size_t bytes) {
  std::lock_guard lock(mutex_);
  if (held_ != 0 && (bytes > limit_ || held_ > limit_ - bytes)) return std::nullopt;
  held_ += bytes;
  return Hold(this, bytes);
}

std::size_t SubmitBudget::held() const {
  std::lock_guard lock(mutex_);
  return held_;
}

void SubmitBudget::release(std::size_t bytes) {
  std::lock_guard lock(mutex_);
  held_ -= bytes;
}

}  // namespace tessera
