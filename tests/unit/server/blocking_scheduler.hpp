// The Scheduler as its unit tests call it: each change is waited for until it is durable,
// as a route waits before it answers, so that a test may read the store, or restart the
// coordinator, right after a call. A change the store refuses throws, except a result,
// which is ResultOutcome::unstored as a worker would hear it.
#pragma once

#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "server/farm/scheduler.hpp"

namespace tessera::test {

class BlockingScheduler {
 public:
  // Calls whichever Scheduler `owner` holds at the time: tests restart the coordinator.
  explicit BlockingScheduler(const std::unique_ptr<Scheduler>& owner) : owner_(owner) {}

  const SchedulerConfig& config() const { return scheduler().config(); }
  JobRecord submit(const std::string& name, int priority, const Scene& scene,
                   const std::string& scene_json, std::vector<int> frames = {}) {
    std::promise<JobRecord> submitted;
    scheduler().submit(
        name, priority, scene, scene_json,
        [&](std::optional<JobRecord> job, const std::string& error) {
          if (job)
            submitted.set_value(*job);
          else
            submitted.set_exception(std::make_exception_ptr(std::runtime_error(error)));
        },
        std::move(frames));
    return submitted.get_future().get();
  }
  std::optional<JobRecord> job(const std::string& id) const { return scheduler().job(id); }
  std::vector<JobRecord> jobs(std::optional<JobState> state, std::size_t limit,
                              std::size_t offset = 0) const {
    return scheduler().jobs(state, limit, offset);
  }
  CancelOutcome cancel(const std::string& id) { return stored(scheduler().cancel(id)); }
  RemoveOutcome remove(const std::string& id) { return stored(scheduler().remove(id)); }
  ControlOutcome set_priority(const std::string& id, int priority) {
    return stored(scheduler().set_priority(id, priority));
  }
  ControlOutcome pause(const std::string& id) { return stored(scheduler().pause(id)); }
  ControlOutcome resume(const std::string& id) { return stored(scheduler().resume(id)); }
  ControlOutcome retry(const std::string& id) { return stored(scheduler().retry(id)); }
  ControlOutcome drain_worker(const std::string& id, bool draining) {
    return stored(scheduler().drain_worker(id, draining));
  }
  ControlOutcome remove_worker(const std::string& id) {
    return stored(scheduler().remove_worker(id));
  }
  std::vector<std::string> job_ids_with_prefix(const std::string& prefix, std::size_t limit) const {
    return scheduler().job_ids_with_prefix(prefix, limit);
  }
  std::optional<std::string> scene_json(const std::string& digest) const {
    std::promise<std::optional<std::string>> scene;
    scheduler().scene_json(digest, [&](std::optional<std::string> json) { scene.set_value(json); });
    return scene.get_future().get();
  }
  std::shared_ptr<const Image> assemble(const std::string& id) const {
    std::promise<std::shared_ptr<const Image>> image;
    scheduler().assemble(
        id, [&](std::shared_ptr<const Image> assembled) { image.set_value(assembled); });
    return image.get_future().get();
  }
  std::optional<std::filesystem::path> image_file(const std::string& id) const {
    return scheduler().image_file(id);
  }
  std::shared_ptr<const Image> assemble_frame(const std::string& id, int frame) const {
    std::promise<std::shared_ptr<const Image>> image;
    scheduler().assemble_frame(
        id, frame, [&](std::shared_ptr<const Image> assembled) { image.set_value(assembled); });
    return image.get_future().get();
  }
  std::optional<std::filesystem::path> frame_image_file(const std::string& id, int frame) const {
    return scheduler().frame_image_file(id, frame);
  }
  std::optional<std::vector<FrameRecord>> frames(const std::string& id) const {
    return scheduler().frames(id);
  }
  void wait_for_images() { scheduler().wait_for_images(); }

  WorkerRecord register_worker(const std::string& name, const std::string& host, int threads,
                               const std::string& secret_sha256 = "") {
    return stored(scheduler().register_worker(name, host, threads, secret_sha256));
  }
  bool worker_known(const std::string& id) const { return scheduler().worker_known(id); }
  std::optional<std::string> worker_with_secret(const std::string& digest) const {
    return scheduler().worker_with_secret(digest);
  }
  std::optional<std::string> lease_holder(const std::string& lease_id) const {
    return scheduler().lease_holder(lease_id);
  }
  std::optional<LeaseRecord> claim(const std::string& worker_id, int max_tiles = 1) {
    return stored(scheduler().claim(worker_id, max_tiles));
  }
  std::optional<LeaseRecord> heartbeat(const std::string& lease_id) {
    return stored(scheduler().heartbeat(lease_id));
  }
  std::optional<LeaseRecord> extend(const std::string& lease_id, int max_tiles) {
    return stored(scheduler().extend(lease_id, max_tiles));
  }
  ResultOutcome complete(const std::string& lease_id, std::span<const TileResult> results) {
    return result(scheduler().complete(lease_id, results));
  }
  ResultOutcome complete(const std::string& lease_id, std::span<const float> pixels,
                         std::uint64_t rays) {
    return result(scheduler().complete(lease_id, pixels, rays));
  }
  std::optional<std::vector<std::size_t>> tile_pixel_counts(
      const std::string& lease_id, std::span<const std::uint64_t> tile_indexes) const {
    return scheduler().tile_pixel_counts(lease_id, tile_indexes);
  }
  void release(const std::string& lease_id) { stored(scheduler().release(lease_id)); }
  void fail_tile(const std::string& lease_id, int tile_index, const std::string& error) {
    stored(scheduler().fail_tile(lease_id, tile_index, error));
  }
  void note_refused_result(const std::string& lease_id, const std::string& why) {
    scheduler().note_refused_result(lease_id, why);
  }
  void touch_worker(const std::string& worker_id) { stored(scheduler().touch_worker(worker_id)); }
  void worker_left(const std::string& worker_id) { stored(scheduler().worker_left(worker_id)); }
  std::vector<WorkerRecord> workers() const { return scheduler().workers(); }
  void expire_leases() { stored(scheduler().expire_leases()); }
  void on_work_available(std::function<void()> callback) {
    scheduler().on_work_available(std::move(callback));
  }

 private:
  Scheduler& scheduler() const { return *owner_; }
  template <class T>
  T stored(Pending<T> pending) {
    const std::string error = scheduler().wait_stored(pending.ticket, pending.wrote);
    if (!error.empty()) throw std::runtime_error(error);
    return std::move(pending.value);
  }
  ResultOutcome result(Pending<ResultOutcome> pending) {
    return scheduler().wait_stored(pending.ticket, pending.wrote).empty() ? pending.value
                                                                          : ResultOutcome::unstored;
  }

  const std::unique_ptr<Scheduler>& owner_;
};

}  // namespace tessera::test
