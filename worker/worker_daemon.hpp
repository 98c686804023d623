// tessera-worker's loop: register with the coordinator, claim a tile (long-polling while
// there is none), render it with every thread while a heartbeat keeps the lease alive,
// upload the pixels, claim again. The coordinator never calls the worker.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "client/http_client.hpp"
#include "worker/lease_heartbeat.hpp"
#include "worker/renderer.hpp"

namespace tessera {

struct WorkerOptions {
  std::string server_url = "http://127.0.0.1:8640";
  std::string name;     // default: the host name
  int threads = 0;      // 0: one per core
  double claim_wait_s = 10;
};

class WorkerDaemon {
 public:
  // `stop` is set (by a signal thread) to ask for a clean exit after the current tile.
  WorkerDaemon(WorkerOptions options, const std::atomic<bool>& stop);

  // Returns the process exit code.
  int run();

 private:
  struct Claimed {
    std::string lease_id;
    std::string job_id;
    std::string scene_digest;
    TileRect rect;
  };

  // Calls `attempt` until it succeeds or stop is requested, backing off (capped) while
  // the coordinator cannot be reached, and saying so once rather than on every try.
  template <typename F>
  auto with_retry(const char* what, F attempt) -> std::optional<decltype(attempt())>;
  void report_reachable(bool reachable, const char* what, const std::string& error);
  bool register_self();
  std::optional<Claimed> claim();
  const Renderer& renderer_for(const std::string& digest);
  // Renders while heartbeating; empty when the lease was lost on the way.
  std::optional<std::vector<float>> render(const Claimed& tile, std::uint64_t& rays);
  void upload(const Claimed& tile, const std::vector<float>& pixels, std::uint64_t rays);
  void release(const Claimed& tile);

  WorkerOptions options_;
  const std::atomic<bool>& stop_;
  HttpClient client_;
  std::string worker_id_;
  std::unique_ptr<LeaseHeartbeat> heartbeat_;  // made at registration, with its interval
  bool unreachable_reported_ = false;
  // Scenes by content digest; a worker usually renders many tiles of one job in a row.
  std::map<std::string, std::unique_ptr<Renderer>> renderers_;
  std::unique_ptr<tbb::task_arena> arena_;  // made once: a new arena per tile costs a lot
};

}  // namespace tessera
