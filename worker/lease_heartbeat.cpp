#include "worker/lease_heartbeat.hpp"

namespace tessera {

LeaseHeartbeat::LeaseHeartbeat(CoordinatorClient& client, std::chrono::milliseconds interval)
    : client_(client), interval_(interval), thread_([this] { run(); }) {}

LeaseHeartbeat::~LeaseHeartbeat() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void LeaseHeartbeat::begin(const std::string& lease_id) {
  {
    std::lock_guard lock(mutex_);
    lease_id_ = lease_id;
    lost_ = false;
    next_beat_ = std::chrono::steady_clock::now() + interval_;
  }
  changed_.notify_all();
}

bool LeaseHeartbeat::end() {
  std::lock_guard lock(mutex_);
  lease_id_.clear();
  return !lost_;
}

void LeaseHeartbeat::run() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    if (lease_id_.empty()) {
      changed_.wait(lock, [&] { return stopping_ || !lease_id_.empty(); });
      continue;
    }
    if (changed_.wait_until(lock, next_beat_, [&] { return stopping_ || lease_id_.empty(); }))
      continue;
    const std::string lease = lease_id_;
    next_beat_ = std::chrono::steady_clock::now() + interval_;
    lock.unlock();
    bool gone = false;
    try {
      gone = !client_.heartbeat(lease);
    } catch (const std::exception&) {
      // Unreachable for now, or an answer other than the lease's (a 503 from a proxy): the
      // lease lives until its timeout; keep rendering.
    }
    lock.lock();
    if (gone && lease_id_ == lease) lost_ = true;
  }
}

}  // namespace tessera
