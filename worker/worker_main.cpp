// tessera-worker: renders tiles for a coordinator.
#include <pthread.h>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include "common/huge_page_malloc.hpp"
#include "common/log_lines.hpp"
#include "common/secret.hpp"
#include "worker/worker_daemon.hpp"

int main(int argc, char** argv) {
  tessera::restart_with_huge_page_malloc(argv);
  tessera::WorkerOptions options;
  std::string log_level = "info";
  CLI::App app{"tessera-worker: renders tiles for a Tessera coordinator"};
  app.add_option("--server", options.server_url, "Coordinator URL")->capture_default_str();
  app.add_option("--threads", options.threads, "Rendering threads (default: one per core)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--name", options.name, "Name shown in `tessera workers` (default: host name)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  std::string token_file;
  app.add_option("--token", options.token,
                 "The coordinator's worker token (default: $TESSERA_WORKER_TOKEN; --token-file "
                 "keeps it out of the process list)");
  app.add_option("--token-file", token_file, "Read the worker token from this file");
  CLI11_PARSE(app, argc, argv);
  try {
    options.token =
        tessera::resolve_secret(options.token, token_file, "TESSERA_WORKER_TOKEN", "worker token");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  // Not a flag: only the test suite injects faults, and local workers inherit it from their
  // coordinator's environment.
  if (const char* fault = std::getenv("TESSERA_FAULT_INJECTION")) options.fault = fault;
  tessera::use_escaped_log_lines();
  spdlog::set_level(spdlog::level::from_str(log_level));

  // Signals go to one thread that turns them into a flag: the loop finishes the tiles in
  // hand. Blocked before any thread starts, so that every thread inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::atomic<bool> stop{false};

  // TBB (ours and Embree's) may use exactly the threads asked for: idle pool threads
  // spinning for work would take CPU from the renderers and from workers beside this one.
  if (options.threads <= 0) options.threads = static_cast<int>(std::thread::hardware_concurrency());
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<std::size_t>(options.threads));
  tessera::WorkerDaemon daemon(options, stop);
  std::atomic<bool> exiting{false};
  std::thread signal_thread([&signals, &stop, &daemon, &exiting] {
    int signal = 0;
    sigwait(&signals, &signal);
    if (exiting) return;  // woken by main below
    spdlog::info("signal {}: finishing the tiles in hand, then exiting", signal);
    stop = true;
    daemon.interrupt();
  });
  const int code = daemon.run();
  // The signal thread must be gone before the daemon it points at.
  exiting = true;
  pthread_kill(signal_thread.native_handle(), SIGTERM);
  signal_thread.join();
  return code;
}
