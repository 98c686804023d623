#include "server/scheduler_entries.hpp"

#include <array>

#include "common/output_transfer.hpp"

namespace tessera {
namespace {

constexpr std::array<std::pair<TileState, const char*>, 3> tile_state_names{{
    {TileState::pending, "pending"},
    {TileState::leased, "leased"},
    {TileState::done, "done"},
}};

}  // namespace

const char* to_string(TileState state) {
  for (const auto& [value, name] : tile_state_names)
    if (value == state) return name;
  return "unknown";
}

std::optional<TileState> tile_state_from_string(std::string_view text) {
  for (const auto& [value, name] : tile_state_names)
    if (text == name) return value;
  return std::nullopt;
}

TileSlot& StagedChange::tile(JobEntry& job, int index) {
  const auto key = std::make_pair(&job, index);
  auto it = tiles.find(key);
  if (it == tiles.end()) it = tiles.emplace(key, job.tiles.at(index)).first;
  return it->second;
}

JobStatus& StagedChange::job(JobEntry& entry) {
  auto it = jobs.find(&entry);
  if (it == jobs.end()) it = jobs.emplace(&entry, entry.status).first;
  return it->second;
}

WorkerEntry& StagedChange::worker(WorkerEntry& entry) {
  auto it = workers.find(&entry);
  if (it == workers.end()) it = workers.emplace(&entry, entry).first;
  return it->second;
}

JobRow job_row(const JobStatus& s) {
  return {s.id,
          s.name,
          s.priority,
          to_string(s.state),
          s.width,
          s.height,
          s.tile_size,
          s.scene_digest,
          s.created_at_ms,
          s.started_at_ms,
          s.finished_at_ms,
          s.error,
          s.rays,
          std::string(output_transfer_name(s.output_transfer))};
}

bool status_from_row(JobRow&& row, JobStatus& s) {
  s.id = std::move(row.id);
  s.name = std::move(row.name);
  const std::optional<JobState> state = job_state_from_string(row.state);
  s.state = state.value_or(JobState::failed);
  s.priority = row.priority;
  s.width = row.width;
  s.height = row.height;
  s.tile_size = row.tile_size;
  s.created_at_ms = row.created_at_ms;
  s.started_at_ms = row.started_at_ms;
  s.finished_at_ms = row.finished_at_ms;
  s.error = std::move(row.error);
  s.rays = row.rays;
  s.scene_digest = std::move(row.scene_digest);
  s.output_transfer = output_transfer_named(row.output_transfer);
  return state.has_value();
}

std::shared_ptr<const Frame> frame_of(const JobEntry& job) {
  auto frame = std::make_shared<Frame>(Frame{job.status.width, job.status.height, {}});
  frame->tiles.reserve(job.tiles.size());
  for (const TileSlot& tile : job.tiles) frame->tiles.push_back(tile.rect);
  return frame;
}

WorkerRow worker_row(const WorkerEntry& w) {
  return {w.info.id,           w.info.name,     w.info.host,
          w.info.threads,      w.info.state,    w.info.tiles_rendered,
          w.info.last_seen_ms, w.secret_sha256, w.info.draining};
}

}  // namespace tessera
