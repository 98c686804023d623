// tessera-server: the coordinator.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/thread_pool.hpp>

#include "common/image/image_io.hpp"
#include "common/text/log_lines.hpp"
#include "common/text/secret.hpp"
#include "server/api/access.hpp"
#include "server/api/api_routes.hpp"
#include "server/api/asset_collector.hpp"
#include "server/api/asset_store.hpp"
#include "server/api/event_hub.hpp"
#include "server/api/farm_events.hpp"
#include "server/api/local_workers.hpp"
#include "server/api/memory_give_back.hpp"
#include "server/farm/sqlite_store.hpp"
#include "server/http/descriptor_limit.hpp"
#include "server/http/http_server.hpp"
#include "server/metrics/http_metrics.hpp"

namespace {

struct ServerOptions {
  std::string listen = "127.0.0.1:8640";
  std::string data_dir = "./tessera-data";
  std::uint64_t max_asset_bytes = std::uint64_t{2} << 30;
  std::int64_t asset_retention_s = 7 * 24 * 3600;
  int local_workers = static_cast<int>(std::thread::hardware_concurrency());
  int worker_threads = 1;
  double lease_timeout_s = 30;
  double heartbeat_interval_s = 5;
  int max_tile_attempts = 3;
  int max_tile_handouts = tessera::SchedulerConfig{}.max_tile_handouts;
  double stall_timeout_s = tessera::SchedulerConfig{}.stall_timeout_ms / 1e3;
  double forget_workers_after_s = tessera::SchedulerConfig{}.forget_workers_after_ms / 1e3;
  std::string log_level = "info";
  std::string log_format = "text";
  std::string port_file;
  tessera::Limits limits;
  std::size_t max_job_bytes = 64 << 20;
  std::size_t submit_memory_budget = std::size_t{1} << 30;
  std::string api_token, api_token_file;
  std::string worker_token, worker_token_file;
  std::string metrics_token, metrics_token_file;
  double event_keepalive_s = 15;
  std::size_t event_queue = tessera::EventLimits{}.queue_events;
  bool insecure = false;
  std::string tls_cert;  // PEM; with tls_key, the coordinator speaks HTTPS
  std::string tls_key;
  std::vector<std::string> allowed_origins;
  std::uint64_t job_memory_budget = tessera::SchedulerConfig{}.job_memory_budget;
  std::uint64_t max_job_tiles = tessera::SchedulerConfig{}.max_job_tiles;
  std::size_t max_connections = 0;           // 0: from the descriptor limit
  std::size_t max_connections_per_peer = 0;  // likewise
};

// A refusal to start that the user can fix with a flag: exit status 2, like a usage error.
struct StartRefused : std::runtime_error {
  using std::runtime_error::runtime_error;
};

bool is_loopback(const std::string& host) {
  if (host == "localhost") return true;
  boost::system::error_code ec;
  const auto address = boost::asio::ip::make_address(host, ec);
  return !ec && address.is_loopback();
}

// "HOST:PORT" or "[IPv6]:PORT".
std::pair<std::string, std::uint16_t> split_listen(const std::string& listen) {
  const auto colon = listen.rfind(':');
  if (colon == std::string::npos) throw CLI::ValidationError("--listen", "expected HOST:PORT");
  std::string host = listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  const int port = std::stoi(listen.substr(colon + 1));
  if (port < 0 || port > 65535) throw CLI::ValidationError("--listen", "port out of range");
  return {host, static_cast<std::uint16_t>(port)};
}

// Once a second: expired leases' tiles go back to the queue, and dead local workers are
// replaced.
// Sends the farm's coalesced progress events (FarmEvents) a few times a second.
void schedule_event_flush(boost::asio::steady_timer& timer, tessera::FarmEvents& events) {
  timer.expires_after(tessera::FarmEvents::kFlushInterval);
  timer.async_wait([&timer, &events](const boost::system::error_code& ec) {
    if (ec) return;
    events.flush();
    schedule_event_flush(timer, events);
  });
}

void schedule_upkeep(boost::asio::steady_timer& timer, tessera::Scheduler& scheduler,
                     tessera::LocalWorkers* workers, const tessera::HttpServer& server,
                     tessera::MemoryGiveBack& memory) {
  timer.expires_after(std::chrono::seconds(1));
  timer.async_wait(
      [&timer, &scheduler, workers, &server, &memory](const boost::system::error_code& ec) {
        if (ec) return;
        scheduler.expire_leases();
        if (workers) workers->restart_exited();
        if (memory.note(server.connection_count()))
          spdlog::debug("connections closed: free memory given back");
        schedule_upkeep(timer, scheduler, workers, server, memory);
      });
}

// The tokens, and the refusal to listen beyond this machine without them.
tessera::AccessTokens checked_tokens(const ServerOptions& options, const std::string& host) {
  using namespace tessera;
  const AccessTokens tokens{
      resolve_secret(options.api_token, options.api_token_file, "TESSERA_API_TOKEN", "API token"),
      resolve_secret(options.worker_token, options.worker_token_file, "TESSERA_WORKER_TOKEN",
                     "worker token"),
      resolve_secret(options.metrics_token, options.metrics_token_file, "TESSERA_METRICS_TOKEN",
                     "metrics token")};
  for (const auto& [file, what] : {std::pair{options.api_token_file, "API token"},
                                   std::pair{options.worker_token_file, "worker token"},
                                   std::pair{options.metrics_token_file, "metrics token"}})
    if (const std::string loose = loose_secret_file(file, what); !loose.empty())
      spdlog::warn("{}", loose);
  if (!is_loopback(host) && (tokens.client.empty() || tokens.worker.empty()) && !options.insecure)
    throw StartRefused(
        "refusing to listen on " + host +
        " without both --api-token and --worker-token: anyone "
        "who can reach it could submit jobs, read every image and pose as a worker. Set both "
        "tokens (or TESSERA_API_TOKEN and TESSERA_WORKER_TOKEN, or the --*-token-file options), "
        "listen on 127.0.0.1, or pass --insecure to accept the risk");
  if (!is_loopback(host) && (tokens.client.empty() || tokens.worker.empty()))
    spdlog::warn("--insecure: listening on {} with {} open to anyone who can reach it", host,
                 tokens.client.empty() && tokens.worker.empty() ? "every route"
                 : tokens.client.empty()                        ? "the client routes"
                                                                : "the worker routes");
  return tokens;
}

tessera::SchedulerConfig scheduler_config(const ServerOptions& options) {
  tessera::SchedulerConfig config;
  config.lease_timeout_ms = static_cast<std::int64_t>(options.lease_timeout_s * 1000);
  config.heartbeat_interval_ms = static_cast<std::int64_t>(options.heartbeat_interval_s * 1000);
  config.max_tile_attempts = options.max_tile_attempts;
  config.max_tile_handouts = options.max_tile_handouts;
  config.stall_timeout_ms = static_cast<std::int64_t>(options.stall_timeout_s * 1000);
  config.forget_workers_after_ms = static_cast<std::int64_t>(options.forget_workers_after_s * 1000);
  config.job_memory_budget = options.job_memory_budget;
  config.max_job_tiles = options.max_job_tiles;
  return config;
}

// Written whole, then renamed: a reader never sees a half-written port.
void write_port_file(const std::string& port_file, unsigned port) {
  const std::filesystem::path temp = port_file + ".tmp";
  std::ofstream(temp) << port << '\n';
  std::filesystem::rename(temp, port_file);
}

std::unique_ptr<tessera::LocalWorkers> start_local_workers(const ServerOptions& options,
                                                           const tessera::AccessTokens& tokens,
                                                           const std::string& host, unsigned port) {
  // Local workers take the worker token from the environment they inherit, never from
  // their command line, which anyone on the machine can read.
  if (!tokens.worker.empty()) ::setenv("TESSERA_WORKER_TOKEN", tokens.worker.c_str(), 1);
  if (options.local_workers <= 0) return nullptr;
  return std::make_unique<tessera::LocalWorkers>(
      tessera::sibling_worker_binary(),
      "http://" + std::string(host == "0.0.0.0" || host == "::" ? "127.0.0.1" : host) + ":" +
          std::to_string(port),
      options.local_workers, options.worker_threads, options.log_level);
}

// Runs `io` on one thread per core (at least two) until it has nothing left to do.
void run_io(boost::asio::io_context& io) {
  const unsigned io_threads = std::max(2u, std::thread::hardware_concurrency());
  std::vector<std::thread> threads;
  for (unsigned i = 1; i < io_threads; ++i) threads.emplace_back([&io] { io.run(); });
  io.run();
  for (auto& thread : threads) thread.join();
}

int run(const ServerOptions& options) {
  using namespace tessera;
  const auto [host, port] = split_listen(options.listen);
  const AccessTokens tokens = checked_tokens(options, host);
  // The cores belong to the local workers and the requests; an image file is written by
  // one low-priority thread, not by a pool of OpenEXR threads competing with them.
  encode_images_on_calling_thread();

  // Before anything opens a file: connections must leave the store its descriptors.
  const DescriptorLimit descriptors = raise_descriptor_limit();
  SqliteStore store(options.data_dir);
  SystemClock clock;
  // Before the scheduler, whose store thread tells them of changes until it stops.
  EventLimits event_limits;
  event_limits.keepalive =
      std::chrono::milliseconds(static_cast<std::int64_t>(options.event_keepalive_s * 1000));
  event_limits.queue_events = options.event_queue;
  EventHub event_hub(event_limits);
  FarmEvents farm_events(event_hub, clock);
  Scheduler scheduler(store, clock, scheduler_config(options));
  scheduler.observe(&farm_events);
  farm_events.rates_from(&scheduler);

  boost::asio::io_context io;
  LongPolls claims(io);
  LongPolls job_waits(io);
  scheduler.on_work_available([&claims] { claims.notify(); });
  scheduler.on_job_finished([&job_waits] { job_waits.notify(); });

  Readiness readiness;
  Router router;
  SubmitBudget submit_budget(options.submit_memory_budget);
  ApiContext context{scheduler,
                     clock,
                     claims,
                     job_waits,
                     options.limits,
                     options.max_job_bytes,
                     std::filesystem::path(options.data_dir) / "tmp"};
  // Downloads are encoded here, so that neither the network's threads nor the store
  // thread wait for an image to be written.
  boost::asio::thread_pool encoders(1);
  context.run_blocking = [&encoders](std::function<void()> work) {
    boost::asio::post(encoders, std::move(work));
  };
  context.submit_budget = &submit_budget;
  // Asset uploads and the checks of submitted scenes' mesh files, beside the encoder.
  AssetStore assets(std::filesystem::path(options.data_dir) / "assets", options.max_asset_bytes);
  context.assets = &assets;
  HttpMetrics http_metrics;
  context.http_metrics = &http_metrics;
  context.metrics_loopback_only = tokens.metrics.empty();
  context.data_dir = options.data_dir;
  context.events = &event_hub;
  context.api_token_required = !tokens.client.empty();
  boost::asio::thread_pool disk(2);
  context.run_disk = [&disk](std::function<void()> work) {
    boost::asio::post(disk, std::move(work));
  };
  add_api_routes(router, context, &readiness);
  // Before the store thread, which it reads scenes through, stops.
  auto collector = std::make_unique<AssetCollector>(
      assets, scheduler, std::chrono::seconds(options.asset_retention_s));

  HttpServerOptions http;
  const tessera::ConnectionCaps caps = connection_caps(descriptors.now);
  http.max_connections = options.max_connections > 0 ? options.max_connections : caps.total;
  http.max_connections_per_peer = options.max_connections_per_peer > 0
                                      ? options.max_connections_per_peer
                                      : std::min(caps.per_peer, http.max_connections);
  spdlog::info("{} file descriptors{}: up to {} connections, {} from one address", descriptors.now,
               descriptors.was < descriptors.now
                   ? " (raised from " + std::to_string(descriptors.was) + ")"
                   : std::string(),
               http.max_connections, http.max_connections_per_peer);
  http.metrics = &http_metrics;
  http.address = host;
  http.port = port;
  // A server without tokens trusts whoever reaches it: on loopback, only this machine's
  // programs, as long as no page under another name (DNS rebinding) gets in.
  http.origins = {options.allowed_origins,
                  is_loopback(host) && (tokens.client.empty() || tokens.worker.empty())};
  const AccessPolicy access(tokens);
  http.authorize = [&access](std::string_view role, std::string_view authorization) {
    return access.check(role, authorization);
  };
  HttpServerOptions plain = http;  // for local workers, beside a TLS port
  http.tls_cert_file = options.tls_cert;
  http.tls_key_file = options.tls_key;
  HttpServer server(io, router, http);
  const bool tls = !options.tls_cert.empty();
  spdlog::info("listening on {}://{}:{} with data in {}", tls ? "https" : "http", host,
               server.port(), options.data_dir);
  if (!options.port_file.empty()) write_port_file(options.port_file, server.port());
  // Local workers reach a TLS coordinator over a plain port of their own on loopback, which
  // never leaves this machine: the certificate need not name 127.0.0.1, nor its CA be
  // trusted here.
  std::unique_ptr<HttpServer> local_port;
  if (tls && options.local_workers > 0) {
    plain.address = "127.0.0.1";
    plain.port = 0;
    local_port = std::make_unique<HttpServer>(io, router, plain);
  }
  const std::unique_ptr<LocalWorkers> workers =
      start_local_workers(options, tokens, local_port ? "127.0.0.1" : host,
                          local_port ? local_port->port() : server.port());
  // SIGHUP: the TLS certificate and key are read again (renewed, say); open connections
  // keep the ones they began with.
  boost::asio::signal_set hangups(io, SIGHUP);
  std::function<void()> await_hangup = [&] {
    hangups.async_wait([&](const boost::system::error_code& ec, int) {
      if (ec) return;
      try {
        server.reload_tls();
        if (tls) spdlog::info("SIGHUP: TLS certificate and key reloaded");
      } catch (const std::exception& e) {
        spdlog::error("SIGHUP: {}; the certificate in use stays", e.what());
      }
      await_hangup();
    });
  };
  await_hangup();
  boost::asio::steady_timer expiry(io);
  tessera::MemoryGiveBack memory_give_back;
  schedule_upkeep(expiry, scheduler, workers.get(), server, memory_give_back);
  boost::asio::steady_timer event_flush(io);
  schedule_event_flush(event_flush, farm_events);
  // The Store is open and the Scheduler has reconciled it (its constructor): /readyz says so.
  readiness.mark_ready();

  // Shutdown: local workers first (they finish or release their tiles while the server
  // still answers), then the server drains its in-flight requests and io.run() returns.
  std::thread stopper;
  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int signal) {
    if (ec) return;
    spdlog::info("signal {}: shutting down", signal);
    readiness.mark_draining();  // /readyz answers 503 while the rest below runs
    stopper = std::thread([&] {
      if (workers) workers->signal_stop();
      claims.close();  // parked claims answer now; the workers see their signal and leave
      job_waits.close();
      event_hub.end_all();  // event streams end: their connections must not hold the drain
      if (workers) workers->stop();
      // Timers and signal sets belong to the io threads.
      boost::asio::post(io, [&expiry, &hangups, &event_flush] {
        expiry.cancel();
        hangups.cancel();
        event_flush.cancel();
      });
      if (local_port) local_port->stop();
      server.stop();
    });
  });

  run_io(io);
  if (stopper.joinable()) stopper.join();
  collector.reset();
  encoders.join();
  disk.join();
  // The long polls go before the scheduler does: it may still finish a job meanwhile.
  scheduler.stop_notifying();
  spdlog::info("stopped");
  return 0;
}

}  // namespace

namespace {

void add_farm_options(CLI::App& app, ServerOptions& options) {
  app.add_option("--listen", options.listen, "HOST:PORT to serve on")->capture_default_str();
  app.add_option("--data-dir", options.data_dir, "Where jobs, tiles and images are kept")
      ->capture_default_str();
  app.add_option("--local-workers", options.local_workers,
                 "tessera-worker processes to start on this machine (0: coordinator only)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--worker-threads", options.worker_threads, "Threads of each local worker")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--lease-timeout", options.lease_timeout_s,
                 "Seconds without a heartbeat before a tile goes back to the queue")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--heartbeat-interval", options.heartbeat_interval_s,
                 "Seconds between a worker's heartbeats")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-asset-bytes", options.max_asset_bytes,
                 "Largest asset (a mesh file, its MTL or .bin) PUT /v1/assets takes")
      ->capture_default_str();
  app.add_option("--asset-retention", options.asset_retention_s,
                 "Seconds after which an asset no submission has named is removed (never one "
                 "a queued or running job needs)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-tile-attempts", options.max_tile_attempts,
                 "Failures of one tile (lease expired, or an error reported) that fail its job")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option("--max-tile-handouts", options.max_tile_handouts,
                 "Times one tile may go out to workers without its result being accepted before "
                 "its job fails")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option(
         "--stall-timeout", options.stall_timeout_s,
         "Seconds a job's tiles may render with none delivered before the job fails; 0: never")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--forget-workers-after", options.forget_workers_after_s,
                 "Seconds after which a worker that left or went silent leaves the worker list; "
                 "0: never")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--log-format", options.log_format,
                 "text, or json: one JSON object per line, with the job, worker and lease ids "
                 "a line names as fields (local workers log alike)")
      ->capture_default_str()
      ->check(CLI::IsMember({"text", "json"}));
  app.add_option("--log-level", options.log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  app.add_option("--port-file", options.port_file,
                 "Write the bound port here once listening (useful with --listen HOST:0)");
}

void add_limit_options(CLI::App& app, ServerOptions& options) {
  // What one job may cost; a scene over a limit is refused with 422 naming it.
  tessera::Limits& limits = options.limits;
  app.add_option("--max-width", limits.max_width, "Largest image width")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-height", limits.max_height, "Largest image height")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-pixels", limits.max_pixels, "Largest width x height")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-samples", limits.max_samples_per_pixel, "Most samples per pixel")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-depth", limits.max_depth, "Deepest recursion (render.max_depth)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-tile-size", limits.max_tile_size, "Largest render.tile_size")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-objects", limits.max_objects, "Most objects")->capture_default_str();
  app.add_option("--max-lights", limits.max_lights, "Most lights")->capture_default_str();
  app.add_option("--max-materials", limits.max_materials, "Most materials")->capture_default_str();
  app.add_option("--max-triangles", limits.max_triangles, "Most triangles, over all objects")
      ->capture_default_str();
  app.add_option("--max-frames", limits.max_frames, "Most frames in an animated scene")
      ->capture_default_str();
  app.add_option("--max-tracks", limits.max_tracks, "Most keyframe tracks in a scene")
      ->capture_default_str();
  app.add_option("--job-memory-budget", options.job_memory_budget,
                 "Bytes of memory the jobs' tiles may take together, reckoned at 256 a tile "
                 "(0: no limit); a job past it is refused, and at start is not loaded")
      ->capture_default_str();
  app.add_option("--max-job-tiles", options.max_job_tiles,
                 "Most tiles of one job, every frame's (0: no limit)")
      ->capture_default_str();
  app.add_option("--max-connections", options.max_connections,
                 "Most open connections (default: the descriptor limit less an eighth, at least "
                 "64, kept for the store's files)");
  app.add_option("--max-connections-per-peer", options.max_connections_per_peer,
                 "Most open connections from one address (default: a quarter of "
                 "--max-connections)");
  app.add_option("--max-job-bytes", options.max_job_bytes,
                 "Largest POST /v1/jobs body in bytes (larger: 413, from the headers)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--submit-memory-budget", options.submit_memory_budget,
                 "Memory in bytes the job submissions being read may take together, reckoned "
                 "as 4x each body; one over it gets 503 with Retry-After")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
}

void add_token_options(CLI::App& app, ServerOptions& options) {
  app.add_option("--api-token", options.api_token,
                 "Secret clients must send (Authorization: Bearer); also $TESSERA_API_TOKEN");
  app.add_option("--api-token-file", options.api_token_file, "Read the API token from this file");
  app.add_option("--worker-token", options.worker_token,
                 "Secret workers must send; also $TESSERA_WORKER_TOKEN");
  app.add_option("--worker-token-file", options.worker_token_file,
                 "Read the worker token from this file");
  app.add_option("--event-keepalive", options.event_keepalive_s,
                 "Seconds between keep-alive comments on an idle event stream (shorter than "
                 "the idle timeout of any proxy in front)")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 3600.0));
  app.add_option("--event-queue", options.event_queue,
                 "Events an event stream's client may fall behind by before it is sent "
                 "\"resync\" instead")
      ->capture_default_str()
      ->check(CLI::Range(1, 10'000'000));
  app.add_option("--metrics-token", options.metrics_token,
                 "The token GET /metrics needs (default: $TESSERA_METRICS_TOKEN; without one, "
                 "/metrics answers this machine only)");
  app.add_option("--metrics-token-file", options.metrics_token_file,
                 "Read the metrics token from this file");
  app.add_flag("--insecure", options.insecure, "Allow a non-loopback --listen without both tokens");
  auto* tls_cert =
      app.add_option("--tls-cert", options.tls_cert,
                     "Serve HTTPS with this PEM certificate (chain); SIGHUP reloads it");
  auto* tls_key = app.add_option("--tls-key", options.tls_key, "The PEM private key of --tls-cert");
  tls_cert->needs(tls_key);
  tls_key->needs(tls_cert);
  app.add_option("--allowed-origin", options.allowed_origins,
                 "A web page's origin (scheme://host:port) that may call this server besides its "
                 "own; repeat for more")
      ->check([](const std::string& origin) {
        const std::size_t scheme = origin.find("://");
        return scheme == std::string::npos || scheme == 0 ||
                       origin.find('/', scheme + 3) != std::string::npos ||
                       origin.size() == scheme + 3
                   ? "an origin is scheme://host[:port], with no path: " + origin
                   : std::string();
      });
}

}  // namespace

int main(int argc, char** argv) {
  ServerOptions options;
  CLI::App app{"tessera-server: the Tessera coordinator"};
  add_farm_options(app, options);
  add_limit_options(app, options);
  add_token_options(app, options);
  CLI11_PARSE(app, argc, argv);
  if (options.log_format == "json") {
    tessera::use_json_log_lines();
    ::setenv("TESSERA_LOG_FORMAT", "json", 1);  // for the local workers
  } else {
    tessera::use_escaped_log_lines();
  }
  spdlog::set_level(spdlog::level::from_str(options.log_level));
  try {
    return run(options);
  } catch (const CLI::Error& e) {
    return app.exit(e);
  } catch (const StartRefused& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
}
