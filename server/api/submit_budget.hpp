// How much memory the job submissions being read may take together. A scene is read in a
// few times its body's bytes (docs/performance.md); without a cap, a handful of large
// submissions at once could take the coordinator past its container's memory limit.
// Unlike BodyBudget, which holds a body back until it fits, a submission over this budget is
// refused at once (503 with Retry-After): its body has already been read, and holding
// it would hold that memory too.
#pragma once

#include <cstddef>
#include <mutex>
#include <optional>

namespace tessera {

class SubmitBudget {
 public:
  explicit SubmitBudget(std::size_t limit) : limit_(limit) {}
  SubmitBudget(const SubmitBudget&) = delete;
  SubmitBudget& operator=(const SubmitBudget&) = delete;

  // A share of the budget, given back when destroyed.
  class Hold {
   public:
    Hold(Hold&& other) noexcept : budget_(other.budget_), bytes_(other.bytes_) {
      other.budget_ = nullptr;
    }
    Hold& operator=(Hold&&) = delete;
    Hold(const Hold&) = delete;
    ~Hold();
    std::size_t bytes() const { return bytes_; }

   private:
    friend class SubmitBudget;
    Hold(SubmitBudget* budget, std::size_t bytes) : budget_(budget), bytes_(bytes) {}
    SubmitBudget* budget_;
    std::size_t bytes_;
  };

  // A hold on `bytes`, or nothing when they do not fit beside what is held now. More than
  // the whole budget fits when nothing else is held: a retry then always gets through.
  std::optional<Hold> try_hold(std::size_t bytes);

  std::size_t limit() const { return limit_; }
  std::size_t held() const;

 private:
  void release(std::size_t bytes);

  const std::size_t limit_;
  mutable std::mutex mutex_;
  std::size_t held_ = 0;
};

}  // namespace tessera
