#include "server/farm/scheduler_entries.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <memory>

#include "common/scene/frame_list.hpp"
#include "common/scene/output_transfer.hpp"
#include "server/farm/tile_order.hpp"

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

JobRecord& StagedChange::job(JobEntry& entry) {
  auto it = jobs.find(&entry);
  if (it == jobs.end()) it = jobs.emplace(&entry, entry.status).first;
  return it->second;
}

WorkerEntry& StagedChange::worker(WorkerEntry& entry) {
  auto it = workers.find(&entry);
  if (it == workers.end()) it = workers.emplace(&entry, entry).first;
  return it->second;
}

JobRow job_row(const JobRecord& s) {
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
          std::string(output_transfer_name(s.output_transfer)),
          s.frames->list};
}

bool status_from_row(JobRow&& row, JobRecord& s) {
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
  bool known = state.has_value();
  if (row.frames.empty()) {
    s.frames = still_frames();
  } else {
    auto frames = std::make_shared<JobFrames>();
    try {
      frames->numbers = parse_frame_list(row.frames, 0, std::numeric_limits<int>::max(),
                                         std::numeric_limits<std::size_t>::max());
      frames->list = std::move(row.frames);
    } catch (const FrameListError&) {
      frames->numbers = {0};  // a row this build cannot read: the job fails, as below
      known = false;
    }
    s.frames = std::move(frames);
  }
  return known;
}

std::shared_ptr<const JobFrames> still_frames() {
  static const auto still = std::make_shared<const JobFrames>(JobFrames{{0}, ""});
  return still;
}

std::vector<std::shared_ptr<const Frame>> frames_of(const JobEntry& job) {
  const std::shared_ptr<const std::vector<TileRect>>& rects = job.rects;
  std::vector<std::shared_ptr<const Frame>> frames;
  for (int slot = 0; slot < job.frame_count(); ++slot)
    frames.push_back(std::make_shared<const Frame>(Frame{job.status.width, job.status.height, rects,
                                                         job.status.id, slot * job.tiles_per_frame,
                                                         static_cast<int>(job.tiles.size())}));
  return frames;
}

namespace {
constexpr std::string_view kFrameKeyMark = ".f";  // a job id never holds a '.'
}  // namespace

std::string image_key(const JobEntry& job, int slot) {
  if (job.frame_count() == 1) return job.status.id;
  return job.status.id + std::string(kFrameKeyMark) +
         std::to_string(job.status.frames->numbers[slot]);
}

std::string spent_tile_error(int index, const TileRect& rect, const TileSlot& tile) {
  return "tile " + std::to_string(index) + " at (" + std::to_string(rect.x) + ", " +
         std::to_string(rect.y) + ") failed " + std::to_string(tile.attempts) +
         " times; the last error: " + tile.last_error;
}

std::string job_of_image(const std::string& key) {
  const std::size_t mark = key.rfind(kFrameKeyMark);
  return mark == std::string::npos ? key : key.substr(0, mark);
}

std::optional<int> slot_of_image(const JobEntry& job, const std::string& key) {
  if (key == job.status.id) return job.frame_count() == 1 ? std::optional<int>(0) : std::nullopt;
  const std::string prefix = job.status.id + std::string(kFrameKeyMark);
  if (job.frame_count() == 1 || !key.starts_with(prefix)) return std::nullopt;
  const std::string number = key.substr(prefix.size());
  if (number.empty() || number.size() > 9 ||
      number.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  const std::vector<int>& numbers = job.status.frames->numbers;
  const auto it = std::lower_bound(numbers.begin(), numbers.end(), std::stoi(number));
  if (it == numbers.end() || *it != std::stoi(number)) return std::nullopt;
  return static_cast<int>(it - numbers.begin());
}

std::vector<int> hand_out_order(const std::vector<TileRect>& rects, int width, int height,
                                int frames) {
  const std::vector<int> one = centre_first_order(rects, width, height);
  std::vector<int> order;
  order.reserve(one.size() * static_cast<std::size_t>(frames));
  const int per_frame = static_cast<int>(rects.size());
  for (int slot = 0; slot < frames; ++slot)
    for (const int index : one) order.push_back(slot * per_frame + index);
  return order;
}

WorkerRow worker_row(const WorkerEntry& w) {
  return {w.info.id,
          w.info.name,
          w.info.host,
          w.info.threads,
          to_string(w.info.state),
          w.info.tiles_rendered,
          w.info.last_seen_ms,
          w.secret_sha256,
          w.info.draining};
}

}  // namespace tessera
