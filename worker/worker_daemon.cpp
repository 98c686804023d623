#include "worker/worker_daemon.hpp"

#include <chrono>
#include <cstring>
#include <thread>
#include <unistd.h>

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "common/scene_parser.hpp"

namespace tessera {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

std::string host_name() {
  char name[256] = {};
  ::gethostname(name, sizeof name - 1);
  return name;
}

constexpr std::size_t kMaxCachedScenes = 2;

}  // namespace

WorkerDaemon::WorkerDaemon(WorkerOptions options, const std::atomic<bool>& stop)
    : options_(std::move(options)),
      stop_(stop),
      client_(options_.server_url,
              std::chrono::milliseconds(static_cast<long>((options_.claim_wait_s + 15) * 1000))) {
  if (options_.name.empty()) options_.name = host_name();
  if (options_.threads <= 0) options_.threads = tbb::this_task_arena::max_concurrency();
  arena_ = std::make_unique<tbb::task_arena>(options_.threads);
}

void WorkerDaemon::report_reachable(bool reachable, const char* what, const std::string& error) {
  if (reachable && unreachable_reported_)
    spdlog::info("coordinator {} reachable again", options_.server_url);
  if (!reachable && !unreachable_reported_)
    spdlog::warn("cannot reach the coordinator at {} ({}: {}); retrying with backoff",
                 options_.server_url, what, error);
  unreachable_reported_ = !reachable;
}

template <typename F>
auto WorkerDaemon::with_retry(const char* what, F attempt) -> std::optional<decltype(attempt())> {
  // At least one try even when stopping: a stopping worker still delivers its last tile.
  auto backoff = 100ms;
  do {
    try {
      auto result = attempt();
      report_reachable(true, what, "");
      return result;
    } catch (const HttpError& e) {
      report_reachable(false, what, e.what());
      for (auto slept = 0ms; slept < backoff && !stop_; slept += 50ms) std::this_thread::sleep_for(50ms);
      backoff = std::min<std::chrono::milliseconds>(backoff * 2, 5s);
    }
  } while (!stop_);
  return std::nullopt;
}

bool WorkerDaemon::register_self() {
  const json body = {{"name", options_.name}, {"host", host_name()}, {"threads", options_.threads}};
  const auto result = with_retry("register", [&] {
    return client_.request("POST", "/v1/workers", body.dump());
  });
  if (!result) return false;
  if (result->status != 201) {
    spdlog::error("registration refused ({}): {}", result->status, result->body);
    return false;
  }
  const json reply = json::parse(result->body);
  worker_id_ = reply.at("id").get<std::string>();
  const double interval_s = reply.value("heartbeat_interval_s", 5.0);
  heartbeat_ = std::make_unique<LeaseHeartbeat>(
      options_.server_url, std::chrono::milliseconds(static_cast<long>(interval_s * 1000)));
  spdlog::info("registered as {} ({}, {} threads)", worker_id_, options_.name, options_.threads);
  return true;
}

std::optional<WorkerDaemon::Claimed> WorkerDaemon::claim() {
  const std::string target =
      "/v1/workers/" + worker_id_ + "/claim?wait_s=" + std::to_string(options_.claim_wait_s);
  const auto result = with_retry("claim", [&] { return client_.request("POST", target); });
  if (!result || result->status == 204) return std::nullopt;
  if (result->status == 404) {  // the coordinator forgot us (a new data dir): join again
    register_self();
    return std::nullopt;
  }
  if (result->status != 200) {
    spdlog::warn("claim answered {}: {}", result->status, result->body);
    std::this_thread::sleep_for(1s);
    return std::nullopt;
  }
  const json lease = json::parse(result->body);
  const json& tile = lease.at("tile");
  return Claimed{lease.at("id"), lease.at("job_id"), lease.at("scene_digest"),
                 TileRect{tile.at("x"), tile.at("y"), tile.at("width"), tile.at("height")}};
}

const Renderer& WorkerDaemon::renderer_for(const std::string& digest) {
  if (auto it = renderers_.find(digest); it != renderers_.end()) return *it->second;
  const auto result = with_retry("scene", [&] { return client_.request("GET", "/v1/scenes/" + digest); });
  if (!result || result->status != 200)
    throw std::runtime_error("cannot fetch scene " + digest);
  if (renderers_.size() >= kMaxCachedScenes) renderers_.erase(renderers_.begin());
  auto renderer = std::make_unique<Renderer>(parse_scene(parse_json_text(result->body)));
  return *renderers_.emplace(digest, std::move(renderer)).first->second;
}

std::optional<std::vector<float>> WorkerDaemon::render(const Claimed& tile, std::uint64_t& rays) {
  const Renderer& renderer = renderer_for(tile.scene_digest);
  heartbeat_->begin(tile.lease_id);
  std::vector<float> pixels(tile.rect.pixel_count() * 3);
  if (options_.threads == 1) {
    rays = renderer.render_tile(tile.rect, pixels).total();
  } else {
    // All threads on one tile, a row each: the tile finishes (and is uploaded) sooner than
    // with one tile per thread, and every pixel is computed the same way either way.
    std::atomic<std::uint64_t> ray_count{0};
    arena_->execute([&] {
      tbb::parallel_for(0, tile.rect.height, [&](int row) {
        if (heartbeat_->lost()) return;
        const TileRect line{tile.rect.x, tile.rect.y + row, tile.rect.width, 1};
        const std::size_t row_floats = static_cast<std::size_t>(tile.rect.width) * 3;
        ray_count += renderer.render_tile(line, std::span<float>(pixels).subspan(row * row_floats, row_floats))
                         .total();
      });
    });
    rays = ray_count;
  }
  if (!heartbeat_->end()) {
    spdlog::info("lease {} was withdrawn; dropping the tile of job {}", tile.lease_id, tile.job_id);
    return std::nullopt;
  }
  return pixels;
}

void WorkerDaemon::upload(const Claimed& tile, const std::vector<float>& pixels,
                          std::uint64_t rays) {
  const std::string body(reinterpret_cast<const char*>(pixels.data()), pixels.size() * sizeof(float));
  const auto result = with_retry("upload", [&] {
    return client_.request("PUT", "/v1/leases/" + tile.lease_id + "/result", body,
                           "application/octet-stream", {{"X-Tessera-Rays", std::to_string(rays)}});
  });
  if (result && result->status != 200)
    spdlog::info("result for lease {} refused ({}): {}", tile.lease_id, result->status, result->body);
}

void WorkerDaemon::release(const Claimed& tile) {
  try {
    client_.request("POST", "/v1/leases/" + tile.lease_id + "/release");
  } catch (const HttpError&) {
    // The lease will expire on its own.
  }
}

int WorkerDaemon::run() {
  if (!register_self()) return stop_ ? 0 : 1;
  while (!stop_) {
    const auto tile = claim();
    if (!tile) continue;
    if (stop_) {  // asked to stop while waiting: give the tile straight back
      release(*tile);
      break;
    }
    std::uint64_t rays = 0;
    try {
      // The upload finishes before the next claim: while this worker still holds the
      // tile's lease, a claim would hand the same lease back (that is how a reconnecting
      // worker recovers its tile) and the tile would be rendered twice.
      if (const auto pixels = render(*tile, rays)) upload(*tile, *pixels, rays);
    } catch (const std::exception& e) {
      spdlog::error("tile of job {} failed: {}", tile->job_id, e.what());
      release(*tile);
    }
  }
  try {
    client_.request("DELETE", "/v1/workers/" + worker_id_);
  } catch (const HttpError&) {
  }
  spdlog::info("worker {} stopped", worker_id_);
  return 0;
}

}  // namespace tessera
