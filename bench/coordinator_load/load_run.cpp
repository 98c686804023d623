#include "bench/coordinator_load/load_run.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <nlohmann/json.hpp>

#include "bench/coordinator_load/heartbeat_pool.hpp"
#include "bench/coordinator_load/server_process.hpp"
#include "bench/coordinator_load/simulated_worker.hpp"
#include "common/protocol/jobs.hpp"
#include "common/protocol/paths.hpp"

namespace tessera::load {
namespace {

namespace net = boost::asio;
using error_code = boost::system::error_code;
using steady = std::chrono::steady_clock;
using namespace std::chrono_literals;

double mib(std::int64_t bytes) { return static_cast<double>(bytes) / (1 << 20); }

double seconds_between(steady::time_point a, steady::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

double own_cpu_seconds() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1e6;
}

// The q-quantile (0..1) of sorted values; 0 for none.
double quantile(const std::vector<float>& sorted, double q) {
  if (sorted.empty()) return 0;
  const auto at = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(at, 1, sorted.size()) - 1];
}

// A scene with nothing to render: only the image and the tile size matter here.
nlohmann::json job_body(const LoadOptions& o) {
  return protocol::to_json(protocol::JobSubmission{
      "coordinator-load",
      50,
      {{"version", 1},
       {"image", {{"width", o.width}, {"height", o.height}}},
       {"camera", {{"eye", {0, 0, 5}}, {"look_at", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_y", 40}}},
       {"render", {{"samples_per_pixel", 1}, {"max_depth", 1}, {"tile_size", o.tile_size}}}},
      std::nullopt});
}

class LoadRun {
 public:
  LoadRun(const LoadOptions& options, const ServerUnderTest& server)
      : options_(options),
        server_(server),
        client_(
            io_, server.endpoint,
            options.api_token.empty() ? "" : "Authorization: Bearer " + options.api_token + "\r\n"),
        heartbeats_(io_, server.endpoint,
                    options.worker_token.empty()
                        ? ""
                        : "Authorization: Bearer " + options.worker_token + "\r\n",
                    state_, 8),
        settle_timer_(io_),
        sample_timer_(io_),
        deadline_(io_) {
    state_.max_tiles = options.max_tiles;
    state_.claim_wait_s = options.claim_wait_s;
    state_.render_time = std::chrono::milliseconds(options.render_ms);
    const std::size_t largest_tile =
        static_cast<std::size_t>(options.tile_size) * options.tile_size * 3 * sizeof(float);
    // 0.5 in every channel: any float would do, the coordinator only checks the size.
    const std::vector<float> half(std::max(state_.max_upload_bytes, largest_tile) / sizeof(float),
                                  0.5f);
    state_.pixels.assign(reinterpret_cast<const char*>(half.data()),
                         reinterpret_cast<const char*>(half.data() + half.size()));
  }

  int run() {
    const std::string worker_auth = options_.worker_token.empty()
                                        ? ""
                                        : "Authorization: Bearer " + options_.worker_token + "\r\n";
    rss_empty_kib_ = rss();
    state_.on_parked = [this] {
      if (++parked_ == options_.workers) settle();
    };
    state_.on_uploaded = [this] {
      if (tiles_total_ > 0 && state_.tiles_accepted >= static_cast<std::uint64_t>(tiles_total_))
        on_job_done();
    };
    state_.on_error = [this] { stop(); };
    state_.heartbeat = [this](const std::string& lease_id, const std::string& secret) {
      heartbeats_.send(lease_id, secret);
    };
    workers_.reserve(static_cast<std::size_t>(options_.workers));
    for (int i = 0; i < options_.workers; ++i) {
      workers_.push_back(
          std::make_unique<SimulatedWorker>(io_, server_.endpoint, worker_auth, state_, i));
      workers_.back()->start();
    }
    deadline_.expires_after(std::chrono::duration_cast<steady::duration>(
        std::chrono::duration<double>(options_.timeout_s)));
    deadline_.async_wait([this](const error_code& ec) {
      if (ec) return;
      state_.fail("timed out after " + std::to_string(options_.timeout_s) + " s with " +
                  std::to_string(state_.tiles_accepted) + " of " + std::to_string(tiles_total_) +
                  " tiles accepted");
      stop();
    });
    sample();
    io_.run();
    if (state_.errors == 0 && options_.wait_for_image && !server_.images_dir.empty())
      wait_for_image();
    if (server_.pid) hwm_kib_ = process_status_kib(server_.pid, "VmHWM");
    if (state_.errors == 0)
      for (const std::string& format : options_.downloads) download(format);
    report();
    return state_.errors == 0 ? 0 : 1;
  }

 private:
  std::int64_t rss() const { return server_.pid ? process_status_kib(server_.pid, "VmRSS") : 0; }

  // Waits for the coordinator to go quiet with every worker parked, then weighs it.
  void settle() {
    settle_started_ = steady::now();
    last_cpu_ = server_.pid ? process_cpu_seconds(server_.pid) : 0;
    settle_timer_.expires_after(250ms);
    settle_timer_.async_wait([this](const error_code& ec) { on_settle_tick(ec); });
  }

  void on_settle_tick(const error_code& ec) {
    if (ec || state_.errors) return;
    const double cpu = server_.pid ? process_cpu_seconds(server_.pid) : 0;
    quiet_ticks_ = cpu == last_cpu_ ? quiet_ticks_ + 1 : 0;
    last_cpu_ = cpu;
    if (quiet_ticks_ < 2 && seconds_between(settle_started_, steady::now()) < 10) {
      settle_timer_.expires_after(250ms);
      settle_timer_.async_wait([this](const error_code& e) { on_settle_tick(e); });
      return;
    }
    rss_idle_kib_ = rss();
    submit();
  }

  void submit() {
    body_ = job_body(options_).dump();
    client_.connect([this](const error_code& ec) {
      if (ec) return fail_and_stop("connect for the submission: " + ec.message());
      submitted_ = steady::now();
      client_.request(
          "POST", std::string(protocol::route::jobs), "Content-Type: application/json\r\n", body_,
          [this](const error_code& e, int status, std::string_view body) {
            if (e || status != 201)
              return fail_and_stop(
                  "submit: " +
                  (e ? e.message() : std::to_string(status) + " " + std::string(body)));
            accepted_ = steady::now();
            protocol::JobStatus job;
            try {
              job = protocol::read_body<protocol::JobStatus>(body);
            } catch (const protocol::ProtocolError& error) {
              return fail_and_stop(std::string("submit: ") + error.what());
            }
            job_id_ = job.id;
            tiles_total_ = job.tiles.total;
            state_.timing = true;
            cpu_at_accept_ = server_.pid ? process_cpu_seconds(server_.pid) : 0;
            if (server_.pid) io_at_accept_ = process_io(server_.pid);
            own_cpu_at_accept_ = own_cpu_seconds();
            machine_at_accept_ = machine_cpu();
            state_.on_uploaded();  // the parked workers may have finished a tiny job already
          });
    });
  }

  void on_job_done() {
    if (state_.finished) return;
    state_.finished = true;
    done_ = steady::now();
    cpu_at_done_ = server_.pid ? process_cpu_seconds(server_.pid) : 0;
    if (server_.pid) io_at_done_ = process_io(server_.pid);
    own_cpu_at_done_ = own_cpu_seconds();
    machine_at_done_ = machine_cpu();
    rss_done_kib_ = rss();
    for (auto& worker : workers_) worker->stop();
    heartbeats_.stop();
    // The coordinator's word that the job is completed, not only our count; on a new
    // connection, since the coordinator closes one that idled through a long run.
    client_.close();
    client_.connect([this](const error_code& connect_error) {
      if (connect_error) {
        state_.record_error("connect for the job status: " + connect_error.message());
        return stop();
      }
      check_job();
    });
  }

  void check_job() {
    client_.request(
        "GET", protocol::job_target(job_id_), "", {},
        [this](const error_code& ec, int status, std::string_view body) {
          if (ec || status != 200) {
            state_.record_error("job status: " + (ec ? ec.message() : std::to_string(status)));
          } else {
            try {
              final_state_ = to_string(protocol::read_body<protocol::JobStatus>(body).state);
            } catch (const protocol::ProtocolError& error) {
              final_state_ = error.what();
            }
            if (final_state_ != "completed") state_.record_error("the job ended " + final_state_);
          }
          stop();
        });
  }

  // Resident memory every 100 ms, for the peak during the run.
  void sample() {
    rss_run_peak_kib_ = std::max(rss_run_peak_kib_, rss());
    sample_timer_.expires_after(100ms);
    sample_timer_.async_wait([this](const error_code& ec) {
      if (!ec) sample();
    });
  }

  void fail_and_stop(const std::string& what) { state_.fail(what); }  // on_error stops

  void stop() {
    state_.finished = true;
    for (auto& worker : workers_) worker->stop();
    heartbeats_.stop();
    client_.close();
    settle_timer_.cancel();
    sample_timer_.cancel();
    deadline_.cancel();
    io_.stop();
  }

  // One image download on a connection of its own, with the coordinator's resident memory
  // sampled every 20 ms while it is answered.
  void download(const std::string& format) {
    net::io_context io(1);
    HttpConnection http(
        io, server_.endpoint,
        options_.api_token.empty() ? "" : "Authorization: Bearer " + options_.api_token + "\r\n");
    net::steady_timer sampler(io);
    Download result{format};
    const std::int64_t before = rss();
    std::function<void()> sample = [&] {
      result.rss_peak_kib = std::max(result.rss_peak_kib, rss());
      sampler.expires_after(20ms);
      sampler.async_wait([&](const error_code& ec) {
        if (!ec) sample();
      });
    };
    const ImageFormat* named = image_format_named(format);
    const std::string target =
        protocol::image_target(job_id_, named ? *named : kImageFormats[0], false);
    const auto start = steady::now();
    http.connect([&](const error_code& ec) {
      if (ec) {
        state_.record_error("connect for the download: " + ec.message());
        sampler.cancel();
        return;
      }
      http.request("GET", target, "", {},
                   [&](const error_code& e, int status, std::string_view body) {
                     result.seconds = seconds_between(start, steady::now());
                     result.bytes = body.size();
                     if (e || status != 200)
                       state_.record_error("download " + format + ": " +
                                           (e ? e.message() : std::to_string(status)));
                     sampler.cancel();
                     http.close();
                   });
    });
    sample();
    io.run();
    result.rss_before_kib = before;
    downloads_.push_back(result);
  }

  void wait_for_image() {
    const auto path = server_.images_dir / (job_id_ + ".exr");
    const auto limit = submitted_ + std::chrono::duration_cast<steady::duration>(
                                        std::chrono::duration<double>(options_.timeout_s));
    while (!std::filesystem::exists(path)) {
      if (steady::now() > limit) {
        state_.record_error("the image " + path.string() + " was not written in time");
        return;
      }
      rss_image_peak_kib_ = std::max(rss_image_peak_kib_, rss());
      std::this_thread::sleep_for(50ms);
    }
    image_written_ = steady::now();
    std::error_code ignored;
    image_bytes_ = std::filesystem::file_size(path, ignored);
  }

  void report() {
    std::vector<float> latency = state_.claim_latency_ms;
    std::sort(latency.begin(), latency.end());
    const double run_s = done_ ? seconds_between(accepted_, *done_) : 0;
    const double server_cpu = cpu_at_done_ - cpu_at_accept_;
    const double own_cpu = own_cpu_at_done_ - own_cpu_at_accept_;
    const double idle_per_worker =
        options_.workers > 0
            ? static_cast<double>(rss_idle_kib_ - rss_empty_kib_) / options_.workers
            : 0;
    nlohmann::json r = {
        {"workers", options_.workers},
        {"width", options_.width},
        {"height", options_.height},
        {"tile_size", options_.tile_size},
        {"max_tiles", options_.max_tiles},
        {"render_ms", options_.render_ms},
        {"tiles", tiles_total_},
        {"tiles_accepted", state_.tiles_accepted},
        {"leases", state_.leases},
        {"uploads", state_.uploads},
        {"empty_claims", state_.empty_claims},
        {"heartbeats", state_.heartbeats},
        {"heartbeats_lost", state_.heartbeats_lost},
        {"server_bytes_read_mib", mib(io_at_done_.rchar - io_at_accept_.rchar)},
        {"server_bytes_written_mib", mib(io_at_done_.wchar - io_at_accept_.wchar)},
        {"server_disk_read_mib", mib(io_at_done_.read_bytes - io_at_accept_.read_bytes)},
        {"server_disk_written_mib", mib(io_at_done_.write_bytes - io_at_accept_.write_bytes)},
        {"errors", state_.errors},
        {"accept_s", submitted_ != steady::time_point{} && accepted_ != steady::time_point{}
                         ? seconds_between(submitted_, accepted_)
                         : 0.0},
        {"run_s", run_s},
        {"tiles_per_s", run_s > 0 ? static_cast<double>(tiles_total_) / run_s : 0.0},
        {"claim_p50_ms", quantile(latency, 0.50)},
        {"claim_p99_ms", quantile(latency, 0.99)},
        {"claim_max_ms", latency.empty() ? 0.0 : latency.back()},
        {"claims_timed", latency.size()},
        {"server_cpu_s", server_cpu},
        {"server_cpu_percent", run_s > 0 ? 100 * server_cpu / run_s : 0.0},
        {"load_cpu_s", own_cpu},
        {"load_cpu_percent", run_s > 0 ? 100 * own_cpu / run_s : 0.0},
        {"machine_busy_percent",
         run_s > 0 ? 100 * (machine_at_done_.busy - machine_at_accept_.busy) / run_s : 0.0},
        {"machine_steal_percent",
         run_s > 0 ? 100 * (machine_at_done_.steal - machine_at_accept_.steal) / run_s : 0.0},
        {"machine_iowait_percent",
         run_s > 0 ? 100 * (machine_at_done_.iowait - machine_at_accept_.iowait) / run_s : 0.0},
        {"cpus", std::thread::hardware_concurrency()},
        {"rss_no_workers_kib", rss_empty_kib_},
        {"rss_idle_workers_kib", rss_idle_kib_},
        {"rss_per_idle_worker_kib", idle_per_worker},
        {"rss_at_completion_kib", rss_done_kib_},
        {"rss_run_peak_sampled_kib", rss_run_peak_kib_},
        {"rss_image_peak_sampled_kib", rss_image_peak_kib_},
        {"vm_hwm_kib", hwm_kib_},
        {"image_s_after_completion",
         image_written_ && done_ ? seconds_between(*done_, *image_written_) : 0.0},
        {"image_bytes", image_bytes_},
        {"job_state", final_state_},
    };
    for (const Download& d : downloads_)
      r["downloads"].push_back({{"format", d.format},
                                {"seconds", d.seconds},
                                {"bytes", d.bytes},
                                {"rss_before_kib", d.rss_before_kib},
                                {"rss_peak_sampled_kib", d.rss_peak_kib}});
    if (state_.errors) r["first_error"] = state_.first_error;
    if (options_.json) {
      std::cout << r.dump() << '\n';
      return;
    }
    const double image_gib =
        static_cast<double>(options_.width) * options_.height * 12 / (1u << 30);
    std::printf(
        "coordinator load: %d workers, %dx%d in %d-pixel tiles (%lld tiles), max_tiles %d, "
        "%d ms per lease\n",
        options_.workers, options_.width, options_.height, options_.tile_size,
        static_cast<long long>(tiles_total_), options_.max_tiles, options_.render_ms);
    std::printf(
        "idle: coordinator RSS %lld KiB with no workers, %lld KiB with %d parked on a claim: "
        "%.1f KiB per idle worker\n",
        static_cast<long long>(rss_empty_kib_), static_cast<long long>(rss_idle_kib_),
        options_.workers, idle_per_worker);
    std::printf("accept: POST /v1/jobs answered in %.3f s\n", r["accept_s"].get<double>());
    if (!done_) {
      std::printf("run: did not finish: %llu of %lld tiles accepted\n",
                  static_cast<unsigned long long>(state_.tiles_accepted),
                  static_cast<long long>(tiles_total_));
      std::printf("errors: %llu; the first: %s\n", static_cast<unsigned long long>(state_.errors),
                  state_.first_error.c_str());
      return;
    }
    std::printf(
        "run: %llu tiles in %.3f s: %.0f tiles/s; %llu leases (%.1f tiles each), %llu uploads, "
        "%llu empty claims\n",
        static_cast<unsigned long long>(state_.tiles_accepted), run_s,
        r["tiles_per_s"].get<double>(), static_cast<unsigned long long>(state_.leases),
        state_.leases ? static_cast<double>(state_.tiles_accepted) / state_.leases : 0.0,
        static_cast<unsigned long long>(state_.uploads),
        static_cast<unsigned long long>(state_.empty_claims));
    std::printf("heartbeats: %llu (%llu found the lease ended, its last upload served first)\n",
                static_cast<unsigned long long>(state_.heartbeats),
                static_cast<unsigned long long>(state_.heartbeats_lost));
    std::printf(
        "coordinator I/O over the run: %.0f MiB read and %.0f MiB written through system calls "
        "(sockets and files), %.0f MiB read from and %.0f MiB written to the disk\n",
        r["server_bytes_read_mib"].get<double>(), r["server_bytes_written_mib"].get<double>(),
        r["server_disk_read_mib"].get<double>(), r["server_disk_written_mib"].get<double>());
    std::printf(
        "claim latency (claims answered with a lease): p50 %.2f ms, p99 %.2f ms, max %.2f ms "
        "(%zu claims)\n",
        quantile(latency, 0.5), quantile(latency, 0.99), r["claim_max_ms"].get<double>(),
        latency.size());
    std::printf(
        "CPU over the run: coordinator %.2f s (%.0f%% of one core), load program %.2f s (%.0f%%)\n",
        server_cpu, r["server_cpu_percent"].get<double>(), own_cpu,
        r["load_cpu_percent"].get<double>());
    std::printf(
        "machine over the run: %.0f%% busy of %u00%% (the coordinator and this program included), "
        "%.0f%% stolen by the hypervisor, %.0f%% idle waiting for the disk\n",
        r["machine_busy_percent"].get<double>(), std::thread::hardware_concurrency(),
        r["machine_steal_percent"].get<double>(), r["machine_iowait_percent"].get<double>());
    std::printf(
        "coordinator RSS: %lld KiB at completion, peak sampled %lld KiB during the run, "
        "%lld KiB while writing the image; VmHWM %lld KiB (the float image is %.2f GiB)\n",
        static_cast<long long>(rss_done_kib_), static_cast<long long>(rss_run_peak_kib_),
        static_cast<long long>(rss_image_peak_kib_), static_cast<long long>(hwm_kib_), image_gib);
    if (image_written_)
      std::printf("image: %llu bytes written %.3f s after the last tile\n",
                  static_cast<unsigned long long>(image_bytes_),
                  r["image_s_after_completion"].get<double>());
    for (const Download& d : downloads_)
      std::printf(
          "download %s: %zu bytes in %.3f s; coordinator RSS %lld KiB before, peak sampled %lld "
          "KiB\n",
          d.format.c_str(), d.bytes, d.seconds, static_cast<long long>(d.rss_before_kib),
          static_cast<long long>(d.rss_peak_kib));
    std::printf("job: %s\n", final_state_.empty() ? "(unknown)" : final_state_.c_str());
    if (state_.errors)
      std::printf("errors: %llu; the first: %s\n", static_cast<unsigned long long>(state_.errors),
                  state_.first_error.c_str());
  }

  const LoadOptions& options_;
  const ServerUnderTest& server_;
  net::io_context io_{1};  // one thread: no locking inside Asio
  LoadState state_;
  std::vector<std::unique_ptr<SimulatedWorker>> workers_;
  HttpConnection client_;
  HeartbeatPool heartbeats_;
  net::steady_timer settle_timer_;
  net::steady_timer sample_timer_;
  net::steady_timer deadline_;
  std::string body_;

  int parked_ = 0;
  int quiet_ticks_ = 0;
  double last_cpu_ = 0;
  steady::time_point settle_started_;
  steady::time_point submitted_;
  steady::time_point accepted_;
  std::optional<steady::time_point> done_;
  std::optional<steady::time_point> image_written_;
  std::string job_id_;
  std::string final_state_;
  std::int64_t tiles_total_ = 0;
  double cpu_at_accept_ = 0, cpu_at_done_ = 0;
  double own_cpu_at_accept_ = 0, own_cpu_at_done_ = 0;
  ProcessIo io_at_accept_, io_at_done_;
  MachineCpu machine_at_accept_, machine_at_done_;
  std::int64_t rss_empty_kib_ = 0, rss_idle_kib_ = 0, rss_done_kib_ = 0;
  std::int64_t rss_run_peak_kib_ = 0, rss_image_peak_kib_ = 0, hwm_kib_ = 0;
  std::uintmax_t image_bytes_ = 0;
  struct Download {
    std::string format;
    double seconds = 0;
    std::size_t bytes = 0;
    std::int64_t rss_before_kib = 0;
    std::int64_t rss_peak_kib = 0;
  };
  std::vector<Download> downloads_;
};

}  // namespace

int run_load(const LoadOptions& options, const ServerUnderTest& server) {
  return LoadRun(options, server).run();
}

}  // namespace tessera::load
