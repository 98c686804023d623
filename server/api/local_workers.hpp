// `--local-workers N`: tessera-worker child processes on this machine, connected over
// loopback, started with the server, restarted if one dies, and stopped with the server.
#pragma once

#include <sys/types.h>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

namespace tessera {

class LocalWorkers {
 public:
  // Starts `count` workers of `threads_each` threads against `server_url`, logging at
  // `log_level` like the server.
  LocalWorkers(std::filesystem::path worker_binary, std::string server_url, int count,
               int threads_each, std::string log_level);
  // Stops any that still run.
  ~LocalWorkers();
  LocalWorkers(const LocalWorkers&) = delete;
  LocalWorkers& operator=(const LocalWorkers&) = delete;

  // Starts a replacement for every worker that has exited, so that a one-command farm
  // never quietly ends up with nobody rendering. Call periodically.
  void restart_exited();
  // SIGTERM to each: they finish or release their tile, then exit. No restarts after this.
  void signal_stop();
  // signal_stop(), then waits until every one has exited.
  void stop();

 private:
  pid_t spawn(int slot) const;

  std::filesystem::path binary_;
  std::string server_url_;
  int threads_each_;
  std::string log_level_;
  std::mutex mutex_;
  std::vector<pid_t> children_;  // by slot; -1 once reaped
  bool stopping_ = false;
};

// The tessera-worker beside the running executable.
std::filesystem::path sibling_worker_binary();

}  // namespace tessera
