// Server-sent events: the farm's changes as numbered events, kept for a while so that a
// stream can resume where it left off (Last-Event-ID), and handed to each subscriber's
// bounded queue. A subscriber that falls behind is not waited for: its queue is emptied
// and it gets a "resync" event, after which the client reloads the state it shows.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "server/http/http_types.hpp"

namespace tessera {

// One event, as it goes on the wire ("id: ...\nevent: ...\ndata: ...\n\n").
struct SentEvent {
  std::uint64_t sequence = 0;
  std::string job_id;   // the job whose stream it is on; "" for none
  bool global = false;  // on GET /v1/events
  std::string text;
};

struct EventLimits {
  // What is kept for resuming streams: the newest events, within both.
  std::size_t kept_events = 100'000;
  std::size_t kept_bytes = 64 << 20;
  // A subscriber's queue: past either, it resyncs.
  std::size_t queue_events = 10'000;
  std::size_t queue_bytes = 16 << 20;
  std::chrono::milliseconds keepalive{15'000};
};

class EventHub;

// One stream's subscription: the BodyStream its connection writes.
class Subscription : public BodyStream {
 public:
  void wait(std::function<void()> ready) override;
  std::string take(bool& ended) override;
  void cancel() override;
  std::string keepalive() const override { return ": keepalive\n\n"; }
  std::chrono::milliseconds keepalive_interval() const override { return keepalive_; }

 private:
  friend class EventHub;
  // Under the hub's lock: queues `event`, or drops the queue for a resync when full.
  // Returns the callback to call (outside the lock) when the subscriber waits for it.
  std::function<void()> push(const std::shared_ptr<const SentEvent>& event,
                             const EventLimits& limits);
  void resync_locked(const std::string& reason);

  std::mutex mutex_;
  std::deque<std::shared_ptr<const SentEvent>> queue_;
  std::size_t queued_bytes_ = 0;
  std::string greeting_;  // a comment sent first, once
  std::string resync_;    // a resync event to send first; "" when none
  std::function<void()> ready_;
  bool cancelled_ = false;
  bool ended_ = false;
  std::chrono::milliseconds keepalive_{15'000};
  std::string epoch_;
};

class EventHub {
 public:
  explicit EventHub(EventLimits limits = {});

  // Sends `data` (JSON text) as an event of `type` to the global stream and/or the
  // stream of `job_id` ("" for none).
  void publish(const std::string& type, const std::string& data, bool global,
               const std::string& job_id = "");
  // A subscription to the global stream (job_id "") or a job's, resuming after
  // `last_event_id` (the Last-Event-ID a client sends) when that is still kept, with a
  // resync event first when it is not.
  std::shared_ptr<Subscription> subscribe(const std::string& job_id,
                                          const std::optional<std::string>& last_event_id);
  // Whether any stream follows `job_id`. When none does, its events of now on are not
  // made (FarmObserver::wants_tiles), and a stream of the job that resumes from an event
  // before now begins with a resync.
  bool follows_or_skips(const std::string& job_id);
  // Ends every stream (shutting down): each subscription ends once its queue is taken.
  void end_all();
  std::size_t subscribers() const;

 private:
  std::string id_of(std::uint64_t sequence) const;

  const EventLimits limits_;
  // Ids are "EPOCH-N": a Last-Event-ID from before a restart names another epoch.
  const std::string epoch_;
  mutable std::mutex mutex_;
  std::uint64_t next_ = 1;
  std::deque<std::shared_ptr<const SentEvent>> kept_;
  std::size_t kept_bytes_ = 0;
  std::vector<std::weak_ptr<Subscription>> global_;
  std::unordered_map<std::string, std::vector<std::weak_ptr<Subscription>>> by_job_;
  // Per job, the last sequence given out when one of its events was not made.
  std::unordered_map<std::string, std::uint64_t> skipped_;
};

}  // namespace tessera
