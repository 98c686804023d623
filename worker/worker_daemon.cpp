#include "worker/worker_daemon.hpp"

#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "common/mesh_files/folder_scene_files.hpp"
#include "common/protocol/limits.hpp"
#include "common/scene/scene_parser.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;

std::string host_name() {
  char name[256] = {};
  ::gethostname(name, sizeof name - 1);
  return name;
}

constexpr std::size_t kMaxCachedScenes = 2;
// Renderers kept of one animated scene: the frame a lease is of, the one before (whose
// tiles may come back after a lost lease) and the next.
constexpr std::size_t kFramesKept = 3;

// A batch lasts about this long: long enough that the round trips between batches cost
// well under 1%, short enough that a higher-priority job waits little for a worker.
constexpr double kBatchSeconds = 0.5;
// Finished tiles wait this long for others to share their upload with.
constexpr auto kUploadGather = std::chrono::milliseconds(50);
// Groups on their way at once, each on a connection of its own: the next is sent while
// one waits for its answer. One at a time held a worker of 16 threads to the round trips
// of its uploads at small tiles (bench/scaling, 1 x 16).
constexpr int kUploadSenders = 2;
// How long one upload may take; the senders' uploads run side by side, so a stopping worker
// waits this long for them at most (tests/deploy/deploy_support.hpp reads it).
constexpr auto kUploadTimeout = std::chrono::seconds(60);
// Groups stay this small even where the coordinator would take more (its
// max_result_bytes): a larger body only holds a tile's pixels longer in both processes.
constexpr std::size_t kPreferredUploadBytes = 16u << 20;
std::vector<ClaimedTile> tiles_of(const protocol::Lease& lease) {
  std::vector<ClaimedTile> tiles;
  tiles.reserve(lease.tiles.size());
  for (const protocol::LeaseTile& tile : lease.tiles)
    tiles.push_back({tile.index, TileRect{tile.x, tile.y, tile.width, tile.height}});
  return tiles;
}

}  // namespace

WorkerDaemon::WorkerDaemon(WorkerOptions options, const std::atomic<bool>& stop)
    : options_(std::move(options)),
      stop_(stop),
      // A claim long-polls for claim_wait_s; the answer may take a while more.
      control_(options_.server_url, options_.token,
               std::chrono::milliseconds(static_cast<long>((options_.claim_wait_s + 15) * 1000)),
               TlsSettings{options_.ca_file}),
      heartbeat_client_(options_.server_url, options_.token, std::chrono::seconds(10),
                        TlsSettings{options_.ca_file}),
      uploads_client_(options_.server_url, options_.token, kUploadTimeout,
                      TlsSettings{options_.ca_file}) {
  if (options_.name.empty()) options_.name = host_name();
  if (options_.threads <= 0) options_.threads = tbb::this_task_arena::max_concurrency();
  arena_ = std::make_unique<tbb::task_arena>(options_.threads);
  uploads_ = std::make_unique<TileUploads>(
      [this](int, const std::vector<FinishedTile>& tiles) {
        return upload(uploading_lease_, tiles);
      },
      kUploadGather, static_cast<std::size_t>(limits_.max_result_tiles), group_bytes(),
      kUploadSenders);
}

WorkerDaemon::~WorkerDaemon() = default;

void WorkerDaemon::report_reachable(bool reachable, const char* what, const std::string& error) {
  // Called from the main thread and the upload thread: exchange() makes one of them say it.
  if (reachable) {
    if (unreachable_reported_.exchange(false))
      spdlog::info("coordinator {} reachable again", options_.server_url);
  } else if (!unreachable_reported_.exchange(true)) {
    spdlog::warn("cannot reach the coordinator at {} ({}: {}); retrying with backoff",
                 options_.server_url, what, error);
  }
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
      if (e.kind() == HttpError::Kind::interrupted) return std::nullopt;  // stopping
      // A certificate this worker does not trust will not become trusted by waiting: before
      // the first registration it stops the worker. Later (a certificate being replaced, say)
      // it is waited out as for a coordinator out of reach.
      if (e.kind() == HttpError::Kind::tls && worker_id_.empty()) throw;
      report_reachable(false, what, e.what());
    } catch (const ApiError& e) {
      // A proxy in front of a coordinator it cannot reach (restarting, say) is as good as
      // no answer: wait as for that. A coordinator's own error stands.
      if (!e.from_gateway()) throw;
      report_reachable(false, what, "HTTP " + std::to_string(e.status()) + " from a proxy");
    }
    for (auto slept = 0ms; slept < backoff && !stop_; slept += 50ms)
      std::this_thread::sleep_for(50ms);
    backoff = std::min<std::chrono::milliseconds>(backoff * 2, 5s);
  } while (!stop_);
  return std::nullopt;
}

bool WorkerDaemon::register_self() {
  protocol::WorkerRegistration registration{options_.name, host_name(), options_.threads};
  std::optional<protocol::Registration> reply;
  try {
    // A coordinator that could not store the registration (a full disk, a store busy
    // elsewhere: 5xx) may next time: waited out as one out of reach, not the end.
    auto backoff = 1s;
    for (bool registered = false; !registered && !stop_;) {
      try {
        reply = with_retry("register", [&] { return control_.register_worker(registration); });
        registered = true;
      } catch (const ApiError& e) {
        if (e.status() < 500) throw;
        spdlog::warn("registration answered {}: {}; trying again in {} s", e.status(), e.what(),
                     backoff.count());
        for (auto slept = 0ms; slept < backoff && !stop_; slept += 50ms)
          std::this_thread::sleep_for(50ms);
        backoff = std::min<std::chrono::seconds>(backoff * 2, 30s);
      }
    }
  } catch (const HttpError& e) {  // TLS (with_retry() waits out everything else)
    spdlog::error("{}", e.what());
    incompatible_ = true;
    incompatible_code_ = 3;
    return false;
  } catch (const ApiError& e) {
    // A refusal (another protocol, a wrong token) stands.
    spdlog::error("registration refused ({}): {}", e.status(), e.what());
    incompatible_ = true;
    // http:// to a coordinator's TLS port: as a TLS failure, a server out of reach.
    if (e.code() == "tls_required") incompatible_code_ = 3;
    return false;
  } catch (const protocol::ProtocolMismatch& e) {
    // A coordinator of another protocol (or one from before version 2, which states no
    // limits) would refuse this worker's results, or misread them: stop here, saying why.
    spdlog::error("{} ({})", e.message(), options_.server_url);
    incompatible_ = true;
    return false;
  } catch (const protocol::ProtocolError& e) {
    spdlog::error(
        "the coordinator at {} answered the registration with something this worker "
        "cannot keep to: {}",
        options_.server_url, e.what());
    incompatible_ = true;
    return false;
  }
  if (!reply) return false;
  limits_ = reply->limits;
  uploads_->set_limits(static_cast<std::size_t>(limits_.max_result_tiles), group_bytes());
  worker_id_ = reply->id;
  // Every later call proves which worker it is, whichever client sends it.
  heartbeat_client_.prove_as(reply->secret);
  uploads_client_.prove_as(reply->secret);
  heartbeat_ = std::make_unique<LeaseHeartbeat>(
      heartbeat_client_,
      std::chrono::milliseconds(static_cast<long>(reply->heartbeat_interval_s * 1000)));
  spdlog::info("registered as {} ({}, {} threads; results of at most {} tiles and {} bytes)",
               worker_id_, options_.name, options_.threads, limits_.max_result_tiles,
               group_bytes());
  return true;
}

std::size_t WorkerDaemon::group_bytes() const {
  return std::min(kPreferredUploadBytes, limits_.max_result_bytes);
}

int WorkerDaemon::batch_tiles(double tile_thread_seconds) const {
  if (tile_thread_seconds <= 0)
    return std::min(options_.threads, limits_.max_batch_tiles);  // nothing measured yet
  const double tiles = kBatchSeconds * options_.threads / tile_thread_seconds;
  const int most = limits_.max_batch_tiles;
  return static_cast<int>(std::clamp(tiles, static_cast<double>(std::min(options_.threads, most)),
                                     static_cast<double>(most)));
}

std::optional<WorkerDaemon::Claimed> WorkerDaemon::claim() {
  std::optional<std::optional<protocol::Lease>> lease;
  try {
    lease = with_retry("claim", [&] {
      return control_.claim(worker_id_, options_.claim_wait_s, batch_tiles(tile_thread_seconds_));
    });
  } catch (const ApiError& e) {
    // The coordinator forgot us (a new data dir), or no longer knows our secret (a store
    // from before secrets): join again.
    if (e.status() == 404 || (e.status() == 403 && e.code() == "wrong_worker")) {
      register_self();
      return std::nullopt;
    }
    spdlog::warn("claim answered {}: {}", e.status(), e.what());
    std::this_thread::sleep_for(1s);
    return std::nullopt;
  }
  if (!lease || !*lease) return std::nullopt;
  const protocol::Lease& l = **lease;
  return Claimed{l.id, l.job_id, l.scene_digest, l.frame, tiles_of(l)};
}

std::optional<std::vector<ClaimedTile>> WorkerDaemon::extend(const std::string& lease_id,
                                                             double tile_thread_seconds) {
  // One try: without an answer the lease simply ends with the tiles it has, and the next
  // claim goes through with_retry().
  try {
    const auto lease = control_.extend(lease_id, batch_tiles(tile_thread_seconds));
    if (!lease) return std::nullopt;
    return tiles_of(*lease);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

AssetCache& WorkerDaemon::asset_cache() {
  if (!assets_) {
    std::filesystem::path dir = options_.asset_cache;
    if (dir.empty())
      dir =
          std::filesystem::temp_directory_path() / ("tessera-assets-" + std::to_string(::getuid()));
    assets_ = std::make_unique<AssetCache>(dir, options_.asset_cache_bytes);
  }
  return *assets_;
}

WorkerDaemon::HeldScene& WorkerDaemon::held_scene(const std::string& digest) {
  if (auto it = scenes_.find(digest); it != scenes_.end()) return it->second;
  std::optional<std::string> scene;
  try {
    scene = with_retry("scene", [&] { return control_.scene(digest); });
  } catch (const ApiError& e) {
    throw std::runtime_error("cannot fetch scene " + digest + ": " + e.what());
  }
  if (!scene) throw std::runtime_error("cannot fetch scene " + digest);
  if (scenes_.size() >= kMaxCachedScenes) scenes_.erase(scenes_.begin());
  HeldScene held;
  // The scene's assets come from the cache, or from the coordinator into it, as the
  // parser meets them. The set lives in the map's node, which never moves.
  held.files = std::make_unique<AssetSceneFiles>(
      [this, digest](const std::string& sha256) -> std::optional<std::filesystem::path> {
        scenes_.at(digest).used_assets.insert(sha256);
        try {
          return asset_cache().get(sha256, [&](const std::filesystem::path& into) {
            const auto fetched = with_retry("asset", [&] {
              control_.scene_asset_to(sha256, into);
              return true;
            });
            if (!fetched) throw std::runtime_error("stopped while fetching asset " + sha256);
          });
        } catch (const ApiError& e) {
          if (e.status() == 404) return std::nullopt;
          throw;
        }
      });
  HeldScene& entry = scenes_.emplace(digest, std::move(held)).first->second;
  try {
    // The coordinator validated the scene against its own limits, which may be above the
    // defaults: here it is only rebuilt.
    entry.frames = std::make_unique<SceneFrames>(std::move(*scene), Limits::none(), nullptr,
                                                 entry.files.get());
  } catch (...) {
    scenes_.erase(digest);
    throw;
  }
  return entry;
}

const Renderer& WorkerDaemon::renderer_for(const std::string& digest, int frame) {
  HeldScene& held = held_scene(digest);
  if (auto it = held.renderers.find(frame); it != held.renderers.end()) return *it->second;
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<Renderer> renderer;
  int shared_with = -1;  // the frame whose geometry it shares, if any
  int placed_from = -1;  // else the frame whose meshes' BVHs it places again, if any
  if (held.renderers.empty()) {
    // The first frame asked for: built whole, from the scene as read.
    Scene first = held.frames->take_first();
    renderer = std::make_unique<Renderer>(
        first.frame == frame ? std::move(first) : held.frames->at(frame, std::move(first)));
    if (!held.used_assets.empty()) asset_cache().trim(held.used_assets);
  } else {
    // From the nearest frame held, whose geometry it shares when the objects stand still.
    const auto nearest = std::min_element(
        held.renderers.begin(), held.renderers.end(), [&](const auto& a, const auto& b) {
          return std::abs(std::int64_t{a.first} - frame) < std::abs(std::int64_t{b.first} - frame);
        });
    const Renderer& from = *nearest->second;
    renderer = std::make_unique<Renderer>(held.frames->at(frame, from.scene()), from);
    if (renderer->shares_geometry_with(from))
      shared_with = nearest->first;
    else if (renderer->shares_meshes_with(from))
      placed_from = nearest->first;
  }
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  // Said once per frame: whether a frame's objects cost a BVH shows here.
  if (shared_with >= 0)
    spdlog::info("scene {} frame {}: ready in {:.3f} s, sharing the geometry of frame {}",
                 digest.substr(0, 12), frame, took.count(), shared_with);
  else if (placed_from >= 0)
    spdlog::info("scene {} frame {}: built in {:.3f} s, placing the mesh BVHs of frame {}",
                 digest.substr(0, 12), frame, took.count(), placed_from);
  else
    spdlog::info("scene {} frame {}: built in {:.3f} s", digest.substr(0, 12), frame, took.count());
  const Renderer& made = *held.renderers.emplace(frame, std::move(renderer)).first->second;
  // The frame furthest from this one goes first: frames go out in order.
  while (held.renderers.size() > kFramesKept) {
    const auto furthest = std::max_element(
        held.renderers.begin(), held.renderers.end(), [&](const auto& a, const auto& b) {
          return std::abs(std::int64_t{a.first} - frame) < std::abs(std::int64_t{b.first} - frame);
        });
    held.renderers.erase(furthest);
  }
  return made;
}

bool WorkerDaemon::upload(const std::string& lease_id, const std::vector<FinishedTile>& tiles) {
  std::string body;
  std::vector<std::uint64_t> indexes;
  std::vector<std::uint64_t> rays;
  std::vector<std::uint64_t> render_us;
  std::size_t bytes = 0;
  for (const FinishedTile& tile : tiles) bytes += tile.pixels.size() * sizeof(float);
  body.reserve(bytes);
  indexes.reserve(tiles.size());
  rays.reserve(tiles.size());
  for (const FinishedTile& tile : tiles) {
    body.append(reinterpret_cast<const char*>(tile.pixels.data()),
                tile.pixels.size() * sizeof(float));
    indexes.push_back(static_cast<std::uint64_t>(tile.index));
    rays.push_back(tile.rays);
    render_us.push_back(tile.render_us);
  }
  try {
    with_retry("upload",
               [&] { return uploads_client_.upload(lease_id, indexes, rays, body, render_us); });
    return true;  // taken, or stopping while unreachable (the lease will expire)
  } catch (const ApiError& e) {
    if (e.status() == 409 || e.status() == 410 || e.status() >= 500) {
      // The lease is no longer ours, or the coordinator could not take it (a full disk fails
      // the job, which says so): nothing this worker sent was wrong.
      spdlog::info("result for lease {} refused ({}): {}", lease_id, e.status(), e.what());
      return false;
    }
    // Anything else is a bug, or a coordinator of another build: said loudly, and reported.
    const std::string error = "the coordinator refused a result of " +
                              std::to_string(tiles.size()) + " tiles (" + std::to_string(bytes) +
                              " bytes) with " + std::to_string(e.status()) + ": " + e.what();
    spdlog::error("lease {}: {}", lease_id, error);
    std::lock_guard lock(refusal_mutex_);
    if (!refusal_) refusal_.emplace(tiles.front().index, error);
    return false;
  } catch (const protocol::ProtocolError& e) {
    // Taken (a 2xx), with an answer this build does not read: the pixels are there.
    spdlog::warn("lease {}: the coordinator's answer to a result: {}", lease_id, e.what());
    return true;
  }
}

void WorkerDaemon::interrupt() {
  control_.interrupt();  // a claim's long poll, or an extension a lease's threads wait on
}

void WorkerDaemon::report_failure(const std::string& lease_id, int tile_index,
                                  const std::string& error) {
  try {
    with_retry("failure report", [&] {
      control_.fail(lease_id, {tile_index, error});
      return true;
    });
  } catch (const ApiError& e) {
    spdlog::warn("the failure report for lease {} was refused ({}): {}", lease_id, e.status(),
                 e.what());
  }
}

void WorkerDaemon::release(const std::string& lease_id) {
  control_.clear_interrupt();  // a stop may have interrupted the client: this must still go out
  try {
    control_.release(lease_id);
  } catch (const std::exception&) {
    // Unreachable, or refused: the lease will expire on its own.
  }
}

int WorkerDaemon::run() {
  if (!register_self()) return stop_ ? 0 : incompatible_ ? incompatible_code_ : 1;
  while (!stop_ && !incompatible_) {
    const auto tile = claim();
    if (!tile) continue;
    if (stop_) {  // asked to stop while waiting: give the tiles straight back
      release(tile->lease_id);
      break;
    }
    try {
      // Every upload finishes before the next claim: while this worker still holds the
      // lease, a claim would hand the same lease back (that is how a reconnecting worker
      // recovers its tiles) and they would be rendered twice.
      render(*tile);
    } catch (const std::exception& e) {
      spdlog::error("lease {} of job {} failed: {}", tile->lease_id, tile->job_id, e.what());
      uploads_->flush();
      heartbeat_->end();
      release(tile->lease_id);
    }
  }
  control_.clear_interrupt();
  try {
    control_.leave(worker_id_);
  } catch (const std::exception&) {
    // Its leases expire and it shows as gone after a while.
  }
  spdlog::info("worker {} stopped after rendering {} tiles", worker_id_, tiles_rendered_.load());
  return incompatible_ ? incompatible_code_ : 0;
}

}  // namespace tessera
