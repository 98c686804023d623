// The bodies of /v1/jobs: a submission, a job's status and a list of them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"
#include "common/protocol/job_state.hpp"
#include "common/protocol/names.hpp"

namespace tessera::protocol {

// Names (of jobs, workers, hosts) are for people and appear in every listing: a name of
// megabytes would make each list that large.
inline constexpr std::size_t kMaxNameBytes = 256;

// POST /v1/jobs (`JobSubmission`).
struct JobSubmission {
  std::string name = "job";
  int priority = 50;
  nlohmann::json scene;  // checked by the scene parser, which names the scene's own errors
  // The frames of an animated scene to render, as render farms write them ("1-100x2",
  // common/scene/frame_list.hpp); every frame of its range when left out.
  std::optional<std::string> frames;
  static constexpr std::size_t kMaxFramesBytes = 4096;
  // Its keys, all there are: the coordinator refuses any other before building its value.
  static constexpr std::string_view kSceneKey = "scene";
  static constexpr std::string_view kKeys[] = {"name", "priority", "frames", kSceneKey};

  // Moves the scene out of `body` rather than copying it: a scene may be tens of megabytes.
  static JobSubmission take(nlohmann::json& body);
  static JobSubmission read(const FieldReader& body);
};
nlohmann::json to_json(const JobSubmission& submission);

// Signs of trouble on a job (`JobHealth`).
struct JobHealth {
  int tile_failures = 0;
  int refused_results = 0;
  int repeated_handouts = 0;
  std::optional<std::string> last_problem;
  double no_progress_s = 0;

  static JobHealth read(const FieldReader& body);
};
nlohmann::json to_json(const JobHealth& health);

// PATCH /v1/jobs/{id} (`JobChange`): what to change; a field left out stays as it is.
struct JobChange {
  std::optional<int> priority;

  static JobChange read(const FieldReader& body);
};
nlohmann::json to_json(const JobChange& change);

// A job's status (`JobStatus`): the answer to a submission, a status request or a cancel.
struct JobStatus {
  struct Tiles {
    int total = 0;
    int done = 0;
    int rendering = 0;
  };
  struct Stats {
    std::uint64_t rays = 0;
    double rays_per_s = 0;
  };
  // The frames it renders: a still is the one frame 0.
  struct Frames {
    std::string list;  // as a frame list ("1-48"), the order they go out in
    int total = 1;
    int done = 0;
    int failed = 0;
    std::string failed_list;  // the failed ones as a frame list; "" when none
    // The first frame neither done nor failed: the one the farm finishes next; none when
    // every frame is.
    std::optional<int> current;
  };
  std::string id;
  std::string name;
  JobState state = JobState::queued;
  int priority = 50;
  int width = 0;
  int height = 0;
  Tiles tiles;
  double progress = 0;
  std::string created_at;  // RFC 3339 (timestamp.hpp)
  std::optional<std::string> started_at;
  std::optional<std::string> finished_at;
  double elapsed_s = 0;
  std::optional<double> eta_s;  // unknown before the first tile is done
  std::optional<std::string> error;
  JobHealth health;
  Stats stats;
  Frames frames;

  static JobStatus read(const FieldReader& body);
};
nlohmann::json to_json(const JobStatus& job);

// A frame's state: pending (no tile done or under lease), rendering, done (its image is
// whole), failed (a tile failed for good; its job goes on with the other frames).
enum class FrameState { pending, rendering, done, failed };
inline constexpr NameTable<FrameState, 4> kFrameStateNames{{
    {FrameState::pending, "pending"},
    {FrameState::rendering, "rendering"},
    {FrameState::done, "done"},
    {FrameState::failed, "failed"},
}};

// One frame of a job (`FrameStatus`): an item of GET /v1/jobs/{id}/frames.
struct FrameStatus {
  int frame = 0;
  FrameState state = FrameState::pending;
  JobStatus::Tiles tiles;
  std::optional<std::string> error;  // failed: why

  static FrameStatus read(const FieldReader& body);
};
nlohmann::json to_json(const FrameStatus& frame);

// GET /v1/jobs/{id}/frames: every frame of the job, in the order they go out.
struct FrameList {
  std::vector<FrameStatus> frames;

  static FrameList read(const FieldReader& body);
};
nlohmann::json to_json(const FrameList& list);

// GET /v1/jobs.
struct JobList {
  std::vector<JobStatus> jobs;

  static JobList read(const FieldReader& body);
};
nlohmann::json to_json(const JobList& list);

// A name (of a job, a worker, a host): a string of at most kMaxNameBytes, without control
// characters (C0, DEL, C1).
std::string read_name(const FieldReader& body, std::string_view key);

// The job states' words, "queued, running, completed, failed or canceled".
JobState read_job_state(const FieldReader& body, std::string_view key);

}  // namespace tessera::protocol
