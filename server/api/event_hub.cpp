#include "server/api/event_hub.hpp"

#include <algorithm>

#include "common/protocol/events.hpp"
#include "server/farm/ids.hpp"

namespace tessera {
namespace {

std::string resync_event(const std::string& reason) {
  return "event: " + std::string(protocol::event::resync) +
         "\ndata: " + protocol::to_json(protocol::Resync{reason}).dump() + "\n\n";
}

}  // namespace

void Subscription::wait(std::function<void()> ready) {
  {
    std::lock_guard lock(mutex_);
    if (cancelled_) return;
    if (queue_.empty() && resync_.empty() && greeting_.empty() && !ended_) {
      ready_ = std::move(ready);
      return;
    }
  }
  ready();
}

std::string Subscription::take(bool& ended) {
  std::lock_guard lock(mutex_);
  std::string text = std::move(greeting_);
  greeting_.clear();
  text += resync_;
  resync_.clear();
  for (const auto& event : queue_) text += event->text;
  queue_.clear();
  queued_bytes_ = 0;
  ended = ended_ && text.empty();
  return text;
}

void Subscription::cancel() {
  std::lock_guard lock(mutex_);
  cancelled_ = true;
  ready_ = nullptr;
  queue_.clear();
  queued_bytes_ = 0;
}

std::function<void()> Subscription::push(const std::shared_ptr<const SentEvent>& event,
                                         const EventLimits& limits) {
  std::lock_guard lock(mutex_);
  if (cancelled_) return nullptr;
  if (resync_.empty()) {
    if (queue_.size() >= limits.queue_events ||
        queued_bytes_ + event->text.size() > limits.queue_bytes) {
      // It reads slower than the farm changes: what it missed is reloaded instead.
      resync_locked("the stream fell behind");
    } else {
      queued_bytes_ += event->text.size();
      queue_.push_back(event);
    }
  }
  return std::exchange(ready_, nullptr);
}

void Subscription::resync_locked(const std::string& reason) {
  queue_.clear();
  queued_bytes_ = 0;
  resync_ = resync_event(reason);
}

EventHub::EventHub(EventLimits limits) : limits_(limits), epoch_(random_hex(8)) {}

std::string EventHub::id_of(std::uint64_t sequence) const {
  return epoch_ + "-" + std::to_string(sequence);
}

void EventHub::publish(const std::string& type, const std::string& data, bool global,
                       const std::string& job_id) {
  std::vector<std::function<void()>> wake;
  {
    std::lock_guard lock(mutex_);
    auto event = std::make_shared<SentEvent>();
    event->sequence = next_++;
    event->job_id = job_id;
    event->global = global;
    event->text = "id: " + id_of(event->sequence) + "\nevent: " + type + "\ndata: " + data + "\n\n";
    std::shared_ptr<const SentEvent> sent = std::move(event);
    kept_bytes_ += sent->text.size();
    kept_.push_back(sent);
    while (!kept_.empty() &&
           (kept_.size() > limits_.kept_events || kept_bytes_ > limits_.kept_bytes)) {
      kept_bytes_ -= kept_.front()->text.size();
      kept_.pop_front();
    }
    const auto deliver = [&](std::vector<std::weak_ptr<Subscription>>& list) {
      std::erase_if(list, [&](const std::weak_ptr<Subscription>& weak) {
        const auto subscription = weak.lock();
        if (!subscription) return true;
        if (auto ready = subscription->push(sent, limits_)) wake.push_back(std::move(ready));
        return false;
      });
    };
    if (global) deliver(global_);
    if (!job_id.empty())
      if (const auto it = by_job_.find(job_id); it != by_job_.end()) {
        deliver(it->second);
        if (it->second.empty()) by_job_.erase(it);
      }
  }
  for (const auto& ready : wake) ready();
}

std::shared_ptr<Subscription> EventHub::subscribe(const std::string& job_id,
                                                  const std::optional<std::string>& last_event_id) {
  auto subscription = std::make_shared<Subscription>();
  subscription->keepalive_ = limits_.keepalive;
  // Sent at once, so that the client knows the stream is open before any event comes.
  subscription->greeting_ = ": open\n\n";
  std::lock_guard lock(mutex_);
  if (last_event_id) {
    // Resumed: the events after it, when every one of them is still kept.
    std::optional<std::uint64_t> last;
    const std::string prefix = epoch_ + "-";
    if (last_event_id->starts_with(prefix)) {
      try {
        std::size_t used = 0;
        const std::string number = last_event_id->substr(prefix.size());
        const unsigned long long value = std::stoull(number, &used);
        if (used == number.size() && value < next_) last = value;
      } catch (const std::exception&) {
      }
    }
    bool kept = last && (kept_.empty() ? *last + 1 == next_ : kept_.front()->sequence <= *last + 1);
    // Events of the job that were not made since then (nobody followed it) are missing.
    if (const auto skip = skipped_.find(job_id);
        kept && !job_id.empty() && skip != skipped_.end() && skip->second >= *last)
      kept = false;
    if (!kept) {
      std::lock_guard sub_lock(subscription->mutex_);
      subscription->resync_locked(last ? "the events since then are not all kept"
                                       : "the coordinator restarted");
    } else {
      const auto from =
          std::lower_bound(kept_.begin(), kept_.end(), *last + 1,
                           [](const std::shared_ptr<const SentEvent>& event,
                              std::uint64_t sequence) { return event->sequence < sequence; });
      for (auto it = from; it != kept_.end(); ++it)
        if ((job_id.empty() && (*it)->global) || (!job_id.empty() && (*it)->job_id == job_id))
          subscription->push(*it, limits_);
    }
  }
  if (job_id.empty())
    global_.push_back(subscription);
  else
    by_job_[job_id].push_back(subscription);
  return subscription;
}

bool EventHub::follows_or_skips(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  if (const auto it = by_job_.find(job_id); it != by_job_.end())
    for (const auto& weak : it->second)
      if (!weak.expired()) return true;
  skipped_[job_id] = next_ - 1;
  return false;
}

void EventHub::end_all() {
  std::vector<std::function<void()>> wake;
  {
    std::lock_guard lock(mutex_);
    const auto end = [&](std::vector<std::weak_ptr<Subscription>>& list) {
      for (const auto& weak : list)
        if (const auto subscription = weak.lock()) {
          std::lock_guard sub_lock(subscription->mutex_);
          subscription->ended_ = true;
          if (subscription->ready_) wake.push_back(std::exchange(subscription->ready_, nullptr));
        }
      list.clear();
    };
    end(global_);
    for (auto& [id, list] : by_job_) end(list);
    by_job_.clear();
  }
  for (const auto& ready : wake) ready();
}

std::size_t EventHub::subscribers() const {
  std::lock_guard lock(mutex_);
  std::size_t count = 0;
  for (const auto& weak : global_) count += !weak.expired();
  for (const auto& [id, list] : by_job_)
    for (const auto& weak : list) count += !weak.expired();
  return count;
}

}  // namespace tessera
