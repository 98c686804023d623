// tessera-worker: renders tiles for a coordinator.
#include <pthread.h>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <thread>

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include "common/image/huge_page_malloc.hpp"
#include "common/net/http_client.hpp"
#include "common/text/log_lines.hpp"
#include "common/text/printable.hpp"
#include "common/text/secret.hpp"
#include "worker/worker_daemon.hpp"

namespace {

// Runs the daemon until it ends, with `signals` (blocked in every thread) turned into `stop`.
int run_daemon(const tessera::WorkerOptions& options, std::atomic<bool>& stop, sigset_t& signals) {
  tessera::WorkerDaemon daemon(options, stop);
  std::atomic<bool> exiting{false};
  std::thread signal_thread([&signals, &stop, &daemon, &exiting] {
    int signal = 0;
    sigwait(&signals, &signal);
    if (exiting) return;  // woken by the Joiner below, not by a signal
    spdlog::info("signal {}: finishing the tiles in hand, then exiting", signal);
    stop = true;
    daemon.interrupt();
  });
  // The signal thread must be gone before the daemon it points at, however run() ends.
  struct Joiner {
    std::atomic<bool>& exiting;
    std::thread& thread;
    ~Joiner() {
      exiting = true;
      pthread_kill(thread.native_handle(), SIGTERM);
      thread.join();
    }
  } joiner{exiting, signal_thread};
  return daemon.run();
}

}  // namespace

int main(int argc, char** argv) {
  tessera::restart_with_huge_page_malloc(argv);
  tessera::WorkerOptions options;
  std::string log_level = "info";
  std::string log_format = "text";
  if (const char* format = std::getenv("TESSERA_LOG_FORMAT"); format && *format)
    log_format = format;
  CLI::App app{"tessera-worker: renders tiles for a Tessera coordinator"};
  app.add_option("--server", options.server_url, "Coordinator URL")->capture_default_str();
  app.add_option("--threads", options.threads, "Rendering threads (default: one per core)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--name", options.name, "Name shown in `tessera workers` (default: host name)");
  app.add_option("--log-format", log_format,
                 "text, or json: one JSON object per line, with the job, worker and lease ids "
                 "a line names as fields (default: $TESSERA_LOG_FORMAT, else text)")
      ->check(CLI::IsMember({"text", "json"}));
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  std::string token_file;
  app.add_option("--token", options.token,
                 "The coordinator's worker token (default: $TESSERA_WORKER_TOKEN; --token-file "
                 "keeps it out of the process list)");
  app.add_option("--token-file", token_file, "Read the worker token from this file");
  app.add_option("--ca-file", options.ca_file,
                 "Trust the CAs of this PEM file for an https:// coordinator, instead of the "
                 "system's (default: $TESSERA_CA_FILE)");
  app.add_option("--asset-cache", options.asset_cache,
                 "Folder for the mesh files of scenes, by digest (default: tessera-assets-UID in "
                 "the temporary directory)");
  app.add_option("--asset-cache-bytes", options.asset_cache_bytes,
                 "Most bytes of assets kept; the least recently used go first")
      ->capture_default_str();
  app.set_version_flag("--version", "tessera-worker " TESSERA_VERSION);
  CLI11_PARSE(app, argc, argv);
  try {
    tessera::parse_base_url(options.server_url);
    options.ca_file = tessera::ca_file_or_env(options.ca_file);
    if (!options.ca_file.empty() && !std::ifstream(options.ca_file))
      throw std::runtime_error("cannot read the CA file " + options.ca_file);
    options.token =
        tessera::resolve_secret(options.token, token_file, "TESSERA_WORKER_TOKEN", "worker token");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", tessera::printable(e.what()).c_str());
    return 2;
  }
  // Not a flag: only the test suite injects faults, and local workers inherit it from their
  // coordinator's environment.
  if (const char* fault = std::getenv("TESSERA_FAULT_INJECTION")) options.fault = fault;
  if (log_format == "json")
    tessera::use_json_log_lines();
  else
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
  // Anything the daemon does not handle itself ends the process with one line, not abort().
  try {
    return run_daemon(options, stop, signals);
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
