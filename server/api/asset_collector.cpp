#include "server/api/asset_collector.hpp"
#include "common/protocol/asset_digest.hpp"

#include <algorithm>
#include <future>
#include <limits>

#include <spdlog/spdlog.h>

#include "server/api/asset_store.hpp"
#include "server/farm/scheduler.hpp"

namespace tessera {

AssetCollector::AssetCollector(AssetStore& store, const Scheduler& scheduler,
                               std::chrono::seconds retention)
    : store_(store), scheduler_(scheduler), retention_(retention), thread_([this] { run(); }) {}

AssetCollector::~AssetCollector() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

std::size_t AssetCollector::collect_once() {
  // The digests of the scenes of queued and running jobs, then the assets those scenes name.
  std::set<std::string> scenes;
  for (const JobState state : {JobState::queued, JobState::running})
    for (const JobRecord& job : scheduler_.jobs(state, std::numeric_limits<std::size_t>::max()))
      scenes.insert(job.scene_digest);
  std::set<std::string> in_use;
  for (const std::string& scene : scenes) {
    std::promise<std::optional<std::string>> text;
    auto arrived = text.get_future();
    scheduler_.scene_json(
        scene, [&text](std::optional<std::string> json) { text.set_value(std::move(json)); });
    // The store thread answers unless it has stopped, when removing nothing is right.
    if (arrived.wait_for(std::chrono::minutes(1)) != std::future_status::ready) return 0;
    const auto json = arrived.get();
    if (!json) return 0;  // a scene of a live job not found: keep everything
    // Every digest the text names counts, generously: a name that merely looks like one keeps
    // an asset, which is the safe side.
    in_use.merge(protocol::digests_named_in(*json));
  }
  return store_.collect(retention_, in_use);
}

void AssetCollector::run() {
  const auto interval = std::clamp<std::chrono::seconds>(retention_ / 4, std::chrono::seconds(1),
                                                         std::chrono::hours(1));
  std::unique_lock lock(mutex_);
  while (!wake_.wait_for(lock, interval, [this] { return stopping_; })) {
    lock.unlock();
    try {
      if (const std::size_t removed = collect_once())
        spdlog::info("removed {} asset(s) no job has named for {} s", removed, retention_.count());
    } catch (const std::exception& e) {
      spdlog::error("asset collection: {}", e.what());
    }
    lock.lock();
  }
}

}  // namespace tessera
