// tessera-worker's loop: register with the coordinator, claim a lease on a batch of tiles
// (long-polling while there is none), render them with every thread, a tile per thread,
// while a heartbeat keeps the lease alive and finished tiles travel back in groups; claim
// again. The coordinator never calls the worker.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include <tbb/task_arena.h>

#include "common/mesh_files/folder_scene_files.hpp"
#include "common/net/coordinator_client.hpp"
#include "common/protocol/limits.hpp"
#include "common/scene/scene_frames.hpp"
#include "tracer/renderer.hpp"
#include "worker/asset_cache.hpp"
#include "worker/batch_tiles.hpp"
#include "worker/lease_heartbeat.hpp"
#include "worker/tile_uploads.hpp"

namespace tessera {

struct WorkerOptions {
  std::string server_url = "http://127.0.0.1:8640";
  std::string name;     // default: the host name
  std::string token;    // the coordinator's worker token; "" for none
  std::string ca_file;  // PEM CAs to trust for an https:// coordinator; "": the system's
  int threads = 0;      // 0: one per core
  double claim_wait_s = 10;
  // Fault injection for the test suite: "crash:N" aborts the process, "error:N" reports
  // a failure, whenever tile N of any job is about to be rendered ("error:N,M" for
  // several tiles). Empty: none.
  std::string fault;
  // Where assets (mesh files) are kept by digest, and how many bytes of them at most.
  // "": a folder of this user's under the system's temporary directory.
  std::string asset_cache;
  std::uint64_t asset_cache_bytes = std::uint64_t{10} << 30;
};

class WorkerDaemon {
 public:
  // `stop` is set (by a signal thread) to ask for a clean exit after the current tile.
  WorkerDaemon(WorkerOptions options, const std::atomic<bool>& stop);
  ~WorkerDaemon();

  // Returns the process exit code.
  int run();
  // Safe from any thread, after setting `stop`: cuts a waiting claim (or extension) short,
  // so that an idle worker exits at once instead of when its long poll ends.
  void interrupt();

 private:
  struct Claimed {
    std::string lease_id;
    std::string job_id;
    std::string scene_digest;
    int frame = 0;                   // the scene's frame every tile is of
    std::vector<ClaimedTile> tiles;  // in the order to render them
  };
  // One scene as this worker holds it: its frames' reader, and a Renderer for each of the
  // few frames it rendered last, each made from another so that a frame whose objects
  // did not move shares their Embree scene and textures.
  struct HeldScene {
    std::set<std::string> used_assets;       // what its mesh files and textures came from
    std::unique_ptr<AssetSceneFiles> files;  // read again for a frame whose objects move
    std::unique_ptr<SceneFrames> frames;
    std::map<int, std::unique_ptr<Renderer>> renderers;  // by frame
  };

  // Calls `attempt` until it succeeds or stop is requested, backing off (capped) while
  // the coordinator cannot be reached, and saying so once rather than on every try.
  template <typename F>
  auto with_retry(const char* what, F attempt) -> std::optional<decltype(attempt())>;
  void report_reachable(bool reachable, const char* what, const std::string& error);
  bool register_self();
  std::optional<Claimed> claim();
  const Renderer& renderer_for(const std::string& digest, int frame);
  HeldScene& held_scene(const std::string& digest);
  AssetCache& asset_cache();  // made on first use
  // What the threads rendering one lease share (render_lease.cpp).
  struct LeaseProgress {
    std::atomic<int> rendered{0};
    // Thread time spent on the lease's tiles so far, for the size of its extensions.
    std::atomic<std::int64_t> busy_ns{0};
    std::mutex failure_mutex;
    std::optional<std::pair<int, std::string>> failure;  // the first tile that failed
    // This lease's time per tile on one thread, or `before` until one is rendered.
    double seconds_per_tile(double before) const {
      const int done = rendered.load();
      return done > 0 ? busy_ns.load() * 1e-9 / done : before;
    }
  };

  // Renders the batch while heartbeating, handing each finished tile to uploads_, and
  // returns once they are all sent. Stops early when the lease is lost or the worker is
  // asked to stop; the tiles not rendered then are released.
  void render(const Claimed& lease);
  // One thread's part of render(): tiles until none is left or the lease ends.
  void render_tiles(const Renderer& renderer, BatchTiles& tiles, LeaseProgress& progress);
  // Reports a refusal or a failed tile, or gives back what was not rendered.
  void end_lease(const Claimed& lease, const LeaseProgress& progress, int count, bool still_held);
  // Asks the coordinator for more tiles of the lease (BatchTiles::Extend), about a
  // batch's worth at `tile_thread_seconds` a tile on one thread.
  std::optional<std::vector<ClaimedTile>> extend(const std::string& lease_id,
                                                 double tile_thread_seconds);
  // Sends one group; false when refused. A refusal other than a lost lease is kept for
  // take_refusal(): the first tile of the group and what the coordinator said.
  bool upload(const std::string& lease_id, const std::vector<FinishedTile>& tiles);
  std::optional<std::pair<int, std::string>> take_refusal();
  void report_failure(const std::string& lease_id, int tile_index, const std::string& error);
  // Applies options_.fault to a tile about to be rendered.
  void inject_fault(int tile_index) const;
  void release(const std::string& lease_id);
  // How many tiles to ask for: about batch_seconds of work at `tile_thread_seconds` a
  // tile (0: nothing measured yet).
  int batch_tiles(double tile_thread_seconds) const;
  // The most bytes of pixels one upload carries: ours, within the coordinator's limit.
  std::size_t group_bytes() const;

  WorkerOptions options_;
  const std::atomic<bool>& stop_;
  // One client per concern, each a pool of kept-alive connections (HttpClient):
  CoordinatorClient
      control_;  // registration, claims, extensions, scenes, reports; interrupted on stop
  CoordinatorClient heartbeat_client_;  // the heartbeat thread's
  CoordinatorClient uploads_client_;    // shared by the upload senders, a connection each
  std::string worker_id_;
  // What the coordinator stated at registration; until then the protocol's defaults.
  ProtocolLimits limits_;
  // The coordinator refused this worker at registration, or speaks another protocol: the
  // worker exits rather than retry what cannot work.
  bool incompatible_ = false;
  int incompatible_code_ = 1;  // the exit code once incompatible_: 3 when TLS failed
  std::mutex refusal_mutex_;
  std::optional<std::pair<int, std::string>> refusal_;  // set by the upload threads
  std::unique_ptr<LeaseHeartbeat> heartbeat_;           // made at registration, with its interval
  std::string uploading_lease_;                         // the lease uploads_ sends for
  std::unique_ptr<TileUploads> uploads_;
  double tile_thread_seconds_ = 0;  // recent time per tile on one thread; 0: none seen yet
  std::string timed_scene_;         // the scene whose tiles tile_thread_seconds_ measures
  std::atomic<bool> unreachable_reported_{false};
  std::atomic<std::uint64_t> tiles_rendered_{0};  // for the log line at exit
  // Scenes by content digest; a worker usually renders many tiles of one job in a row.
  std::map<std::string, HeldScene> scenes_;
  std::unique_ptr<AssetCache> assets_;
  std::unique_ptr<tbb::task_arena> arena_;  // made once: a new arena per tile costs a lot
};

}  // namespace tessera
