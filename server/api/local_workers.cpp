#include "server/api/local_workers.hpp"

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <csignal>
#include <cstring>
#include <stdexcept>

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

LocalWorkers::LocalWorkers(std::filesystem::path worker_binary, std::string server_url, int count,
                           int threads_each, std::string log_level)
    : binary_(std::move(worker_binary)),
      server_url_(std::move(server_url)),
      threads_each_(threads_each),
      log_level_(std::move(log_level)) {
  for (int slot = 0; slot < count; ++slot) children_.push_back(spawn(slot));
  spdlog::info("started {} local worker(s) of {} thread(s) each", count, threads_each);
}

pid_t LocalWorkers::spawn(int slot) const {
  const std::string name = "local-" + std::to_string(slot + 1);
  const std::string threads = std::to_string(threads_each_);
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    // The child dies with the server even if the server is killed outright.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    ::execl(binary_.c_str(), "tessera-worker", "--server", server_url_.c_str(), "--name",
            name.c_str(), "--threads", threads.c_str(), "--log-level", log_level_.c_str(),
            static_cast<char*>(nullptr));
    std::fprintf(stderr, "cannot start %s: %s\n", binary_.c_str(), std::strerror(errno));
    ::_exit(127);
  }
  return pid;
}

LocalWorkers::~LocalWorkers() { stop(); }

void LocalWorkers::restart_exited() {
  std::lock_guard lock(mutex_);
  if (stopping_) return;
  for (std::size_t slot = 0; slot < children_.size(); ++slot) {
    int status = 0;
    if (::waitpid(children_[slot], &status, WNOHANG) != children_[slot]) continue;
    spdlog::warn("local worker {} (pid {}) {} {}; starting another", slot + 1, children_[slot],
                 WIFSIGNALED(status) ? "was killed by signal" : "exited with status",
                 WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
    children_[slot] = spawn(static_cast<int>(slot));
  }
}

void LocalWorkers::signal_stop() {
  std::lock_guard lock(mutex_);
  stopping_ = true;
  for (pid_t pid : children_) ::kill(pid, SIGTERM);
}

void LocalWorkers::stop() {
  signal_stop();
  std::vector<pid_t> children;
  {
    // Not held while waiting: the upkeep timer must not block an io thread behind us.
    std::lock_guard lock(mutex_);
    children.swap(children_);
  }
  for (pid_t pid : children) {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (!children.empty()) spdlog::info("local workers stopped");
}

}  // namespace tessera
