#include "server/local_workers.hpp"

#include <csignal>
#include <cstring>
#include <stdexcept>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

namespace tessera {

std::filesystem::path sibling_worker_binary() {
  const auto self = std::filesystem::read_symlink("/proc/self/exe");
  // Installed side by side, or in the build tree's worker/ next to server/.
  for (const auto& candidate : {self.parent_path() / "tessera-worker",
                                self.parent_path().parent_path() / "worker" / "tessera-worker"})
    if (std::filesystem::exists(candidate)) return candidate;
  throw std::runtime_error("cannot find tessera-worker beside " + self.string());
}

LocalWorkers::LocalWorkers(const std::filesystem::path& worker_binary,
                           const std::string& server_url, int count, int threads_each,
                           const std::string& log_level) {
  for (int i = 0; i < count; ++i) {
    const std::string name = "local-" + std::to_string(i + 1);
    const std::string threads = std::to_string(threads_each);
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
      // The child dies with the server even if the server is killed outright.
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      ::execl(worker_binary.c_str(), "tessera-worker", "--server", server_url.c_str(), "--name",
              name.c_str(), "--threads", threads.c_str(), "--log-level", log_level.c_str(),
              static_cast<char*>(nullptr));
      std::fprintf(stderr, "cannot start %s: %s\n", worker_binary.c_str(), std::strerror(errno));
      ::_exit(127);
    }
    children_.push_back(pid);
  }
  spdlog::info("started {} local worker(s) of {} thread(s) each", count, threads_each);
}

LocalWorkers::~LocalWorkers() { stop(); }

void LocalWorkers::signal_stop() {
  for (pid_t pid : children_) ::kill(pid, SIGTERM);
}

void LocalWorkers::stop() {
  signal_stop();
  for (pid_t pid : children_) {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (!children_.empty()) spdlog::info("local workers stopped");
  children_.clear();
}

}  // namespace tessera
