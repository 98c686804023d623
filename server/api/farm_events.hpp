// The scheduler's changes as server-sent events (EventHub): what GET /v1/events and
// GET /v1/jobs/{id}/events send. A job's state or priority and a worker's arrival or
// departure go out at once; progress (a job's counts, a worker's current tile) is
// coalesced and goes out at each flush(), so that a farm rendering a thousand tiles a
// second does not send a thousand job events a second to every dashboard.
#pragma once

#include <map>
#include <mutex>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/protocol/events.hpp"
#include "server/api/event_hub.hpp"
#include "server/farm/clock.hpp"
#include "server/farm/scheduler.hpp"

namespace tessera {

class FarmEvents : public FarmObserver {
 public:
  FarmEvents(EventHub& hub, const Clock& clock) : hub_(hub), clock_(clock) {}

  void jobs_changed(const std::vector<JobRecord>& jobs) override;
  void tiles_changed(const std::vector<TileChange>& tiles) override;
  void workers_changed(const std::vector<std::pair<WorkerRecord, WorkerChange>>& workers) override;
  void job_removed(const std::string& job_id) override;
  bool wants_tiles(const std::string& job_id) override;
  // Sends the newest state of the jobs and workers whose progress changed since the last
  // flush. Called every kFlushInterval.
  void flush();
  static constexpr std::chrono::milliseconds kFlushInterval{250};
  // Where flush() reads the workers' current rates (tiles a minute, rays a second), which
  // the changes themselves do not carry; none: they go as 0.
  void rates_from(const Scheduler* scheduler) { scheduler_ = scheduler; }

 private:
  void send_job(const JobRecord& job);
  void send_worker(const WorkerRecord& worker, WorkerChange change);

  EventHub& hub_;
  const Clock& clock_;
  const Scheduler* scheduler_ = nullptr;
  std::mutex mutex_;
  // What was last sent of each unfinished job: its state and priority.
  std::unordered_map<std::string, std::pair<JobState, int>> told_;
  std::map<std::string, JobRecord> dirty_jobs_;
  std::map<std::string, WorkerRecord> dirty_workers_;
};

// A tile as GET /v1/jobs/{id}/tiles lists it, and as the data of a "tile" event, which
// adds a done tile's pixels (docs/api.md, "Events").
protocol::TileStatus tile_status(const FarmObserver::TileChange& tile);
std::string tile_event_data(const FarmObserver::TileChange& tile);

}  // namespace tessera
