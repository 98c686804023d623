// Garbage collection of the coordinator's assets: on a thread of its own, every quarter of
// the retention (at most hourly), the assets that no submission has named for
// `--asset-retention` are removed, except any that the scene of a queued or running job
// names.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <thread>

namespace tessera {

class AssetStore;
class Scheduler;

class AssetCollector {
 public:
  AssetCollector(AssetStore& store, const Scheduler& scheduler, std::chrono::seconds retention);
  ~AssetCollector();  // stops the thread
  AssetCollector(const AssetCollector&) = delete;
  AssetCollector& operator=(const AssetCollector&) = delete;

  // One pass, on the calling thread: how many assets it removed.
  std::size_t collect_once();

 private:
  void run();

  AssetStore& store_;
  const Scheduler& scheduler_;
  const std::chrono::seconds retention_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace tessera
