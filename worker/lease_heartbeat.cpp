#include "worker/lease_heartbeat.hpp"

#include "client/http_client.hpp"

namespace tessera {

LeaseHeartbeat::LeaseHeartbeat(std::string server_url, std::string token,
                               std::chrono::milliseconds interval)
    : server_url_(std::move(server_url)),
      token_(std::move(token)),
      interval_(interval),
      thread_([this] { run(); }) {}

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
  HttpClient client(server_url_, std::chrono::seconds(10));
  client.set_bearer_token(token_);
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
      gone = client.request("POST", "/v1/leases/" + lease + "/heartbeat").status == 410;
    } catch (const HttpError&) {
      // Unreachable for now: the lease lives until its timeout; keep rendering.
    }
    lock.lock();
    if (gone && lease_id_ == lease) lost_ = true;
  }
}

}  // namespace tessera
