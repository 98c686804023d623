// tessera_coordinator_load: hundreds to a thousand simulated workers against one
// tessera-server on loopback, on one thread. It starts the server itself (--server-bin)
// or takes one that runs (--server), and reports tiles per second, claim latency, the
// coordinator's CPU and its memory per idle worker, and for a big frame the time to accept
// the job and the coordinator's peak memory while it assembles and writes the image.
//
//   tessera_coordinator_load --server-bin build/server/tessera-server --workers 1000
//   tessera_coordinator_load --server-bin build/server/tessera-server --workers 1000
//       --width 16384 --height 16384 --tile-size 16  (one line)
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include "bench/coordinator_load/load_run.hpp"
#include "bench/coordinator_load/server_process.hpp"

namespace {

using tessera::load::LoadOptions;

// A thousand connections need more descriptors than the usual soft limit of 1024, here
// and in the server this program starts (which inherits the limit).
void raise_file_limit() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return;
  limit.rlim_cur = limit.rlim_max;
  ::setrlimit(RLIMIT_NOFILE, &limit);
}

boost::asio::ip::tcp::endpoint resolve(const std::string& url) {
  // "http://HOST:PORT[/]"
  std::string rest = url.rfind("http://", 0) == 0 ? url.substr(7) : url;
  if (!rest.empty() && rest.back() == '/') rest.pop_back();
  const auto colon = rest.rfind(':');
  const std::string host = colon == std::string::npos ? rest : rest.substr(0, colon);
  const std::string port = colon == std::string::npos ? "80" : rest.substr(colon + 1);
  boost::asio::io_context io;
  boost::asio::ip::tcp::resolver resolver(io);
  return *resolver.resolve(host, port).begin();
}

}  // namespace

int main(int argc, char** argv) {
  LoadOptions options;
  std::string server_url;
  std::string server_bin;
  int server_pid = 0;
  std::string data_dir;
  bool keep_data = false;
  std::string server_log_level = "warn";
  std::vector<std::string> server_args;
  bool no_image_wait = false;

  CLI::App app{"tessera_coordinator_load: simulated workers against one tessera-server"};
  auto* bin = app.add_option("--server-bin", server_bin,
                             "Start this tessera-server on a free loopback port and measure it");
  app.add_option("--server", server_url, "Or load a running coordinator at this URL")
      ->excludes(bin);
  app.add_option("--server-pid", server_pid,
                 "With --server: its process id, for the /proc figures");
  app.add_option("--data-dir", data_dir,
                 "With --server-bin: where it keeps its data (default: a fresh directory, removed "
                 "afterwards); with --server: its --data-dir, to wait for the image file");
  app.add_flag("--keep-data", keep_data, "Keep the data directory of the server it started");
  app.add_option("--server-log-level", server_log_level, "The started server's --log-level")
      ->capture_default_str();
  app.add_option("--server-arg", server_args, "One more argument for the started server (repeat)")
      ->allow_extra_args(false);
  app.add_option("--workers", options.workers, "Simulated workers, one connection each")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--width", options.width, "Image width")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--height", options.height, "Image height")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--tile-size", options.tile_size, "Tile edge in pixels")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-tiles", options.max_tiles, "max_tiles of every claim (1 to 256)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--render-ms", options.render_ms,
                 "Milliseconds each lease is rendered before its upload (0: none, the most load)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--claim-wait", options.claim_wait_s, "wait_s of every claim")
      ->capture_default_str()
      ->check(CLI::Range(0, 60));
  app.add_option("--timeout", options.timeout_s, "Seconds the whole run may take")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_flag("--no-image-wait", no_image_wait,
               "Stop at the last tile, not once the image file is written");
  app.add_option("--api-token", options.api_token, "Bearer token for the job routes");
  app.add_option("--worker-token", options.worker_token, "Bearer token for the worker routes");
  app.add_flag("--json", options.json, "Print the report as one JSON object");
  app.add_option("--download", options.downloads,
                 "Once the image file is written, download the image in this format (exr, png, "
                 "jpg, tif; repeat for more), timed, with the coordinator's memory sampled")
      ->allow_extra_args(false);
  CLI11_PARSE(app, argc, argv);
  if (server_bin.empty() && server_url.empty()) {
    std::cerr << "give --server-bin PATH or --server URL\n";
    return 2;
  }
  options.wait_for_image = !no_image_wait;
  raise_file_limit();

  try {
    tessera::load::ServerUnderTest server;
    std::unique_ptr<tessera::load::ServerProcess> process;
    std::filesystem::path temp_dir;
    if (!server_bin.empty()) {
      std::filesystem::path dir = data_dir;
      if (dir.empty()) {
        dir = temp_dir = std::filesystem::temp_directory_path() /
                         ("tessera-coordinator-load-" + std::to_string(::getpid()));
        std::filesystem::remove_all(dir);
      }
      std::vector<std::string> args{
          "--log-level",     server_log_level,
          "--max-width",     std::to_string(options.width),
          "--max-height",    std::to_string(options.height),
          "--max-pixels",    std::to_string(static_cast<long long>(options.width) * options.height),
          "--max-tile-size", std::to_string(options.tile_size)};
      args.insert(args.end(), server_args.begin(), server_args.end());
      if (!options.worker_token.empty())
        args.insert(args.end(), {"--worker-token", options.worker_token});
      if (!options.api_token.empty()) args.insert(args.end(), {"--api-token", options.api_token});
      process = std::make_unique<tessera::load::ServerProcess>(server_bin, dir, args);
      server.endpoint = {boost::asio::ip::make_address("127.0.0.1"), process->port()};
      server.pid = process->pid();
      server.images_dir = dir / "data" / "images";
      // On stderr, for a profiler to attach to: perf record -g -p PID
      std::cerr << "tessera_coordinator_load: started " << server_bin << ", pid " << server.pid
                << ", port " << process->port() << ", data in " << dir.string() << std::endl;
    } else {
      server.endpoint = resolve(server_url);
      server.pid = server_pid;
      if (!data_dir.empty()) server.images_dir = std::filesystem::path(data_dir) / "images";
    }
    const int status = tessera::load::run_load(options, server);
    process.reset();  // the server stops before its data goes
    if (!temp_dir.empty() && !keep_data) std::filesystem::remove_all(temp_dir);
    return status;
  } catch (const std::exception& e) {
    std::cerr << "tessera_coordinator_load: " << e.what() << '\n';
    return 1;
  }
}
