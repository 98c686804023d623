// `--local-workers N`: tessera-worker child processes on this machine, connected over
// loopback, started with the server and stopped with it.
#pragma once

#include <filesystem>
#include <string>
#include <sys/types.h>
#include <vector>

namespace tessera {

class LocalWorkers {
 public:
  // Starts `count` workers of `threads_each` threads against `server_url`, logging at
  // `log_level` like the server.
  LocalWorkers(const std::filesystem::path& worker_binary, const std::string& server_url,
               int count, int threads_each, const std::string& log_level);
  // Stops any that still run.
  ~LocalWorkers();
  LocalWorkers(const LocalWorkers&) = delete;
  LocalWorkers& operator=(const LocalWorkers&) = delete;

  // SIGTERM to each: they finish or release their tile, then exit.
  void signal_stop();
  // signal_stop(), then waits until every one has exited.
  void stop();

 private:
  std::vector<pid_t> children_;
};

// The tessera-worker beside the running executable.
std::filesystem::path sibling_worker_binary();

}  // namespace tessera
