// Keeps the lease of the tile being rendered alive: one thread for the worker's life, with
// a client of its own (the worker's lease concern), so heartbeats never wait behind a
// claim or an upload.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "common/net/coordinator_client.hpp"

namespace tessera {

class LeaseHeartbeat {
 public:
  // `client` is used by this heartbeat's thread only, and outlives it.
  LeaseHeartbeat(CoordinatorClient& client, std::chrono::milliseconds interval);
  ~LeaseHeartbeat();
  LeaseHeartbeat(const LeaseHeartbeat&) = delete;
  LeaseHeartbeat& operator=(const LeaseHeartbeat&) = delete;

  // Starts heartbeating `lease_id`; the first beat goes out one interval from now.
  void begin(const std::string& lease_id);
  // Stops heartbeating. Returns false when the coordinator said the lease was lost.
  bool end();
  // True once the coordinator answered that the current lease is gone (410).
  bool lost() const { return lost_; }

 private:
  void run();

  CoordinatorClient& client_;
  std::chrono::milliseconds interval_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::string lease_id_;  // "" when idle
  std::chrono::steady_clock::time_point next_beat_;
  std::atomic<bool> lost_{false};
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace tessera
