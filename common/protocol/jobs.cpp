#include "common/protocol/jobs.hpp"

#include "common/text/printable.hpp"

namespace tessera::protocol {
namespace {

using nlohmann::json;

json string_or_null(const std::optional<std::string>& text) {
  return text ? json(*text) : json(nullptr);
}

int int_of(const FieldReader& body, std::string_view key) {
  return static_cast<int>(body.integer(key, 0, std::numeric_limits<int>::max()));
}

// Everything but the scene, whose presence is checked.
JobSubmission read_settings(const FieldReader& body) {
  body.only(JobSubmission::kKeys);
  JobSubmission submission;
  if (body.has("name")) submission.name = read_name(body, "name");
  // Its syntax is checked against the scene's range by the coordinator, which names both.
  if (body.has("frames")) {
    submission.frames = body.string("frames");
    if (submission.frames->size() > JobSubmission::kMaxFramesBytes)
      body.fail("frames", "must be at most " + std::to_string(JobSubmission::kMaxFramesBytes) +
                              " bytes, got " + std::to_string(submission.frames->size()));
  }
  if (const auto priority = body.optional_integer("priority", 0, 100))
    submission.priority = static_cast<int>(*priority);
  body.object(JobSubmission::kSceneKey);  // the scene parser reads what is inside
  return submission;
}

}  // namespace

std::string read_name(const FieldReader& body, std::string_view key) {
  std::string name = body.string(key);
  if (name.size() > kMaxNameBytes)
    body.fail(key, "must be at most " + std::to_string(kMaxNameBytes) + " bytes, got " +
                       std::to_string(name.size()));
  // A name is shown in lists, terminals and logs: it may not hold what would steer them.
  if (const std::size_t at = find_control_character(name); at != std::string::npos)
    body.fail(key, "must not hold control characters; byte " + std::to_string(at) + " is " +
                       control_sequence_at(name, at));
  return name;
}

JobState read_job_state(const FieldReader& body, std::string_view key) {
  const auto state = value_in(kJobStateNames, body.string(key));
  if (!state) body.fail(key, "must be " + names_of(kJobStateNames));
  return *state;
}

JobChange JobChange::read(const FieldReader& body) {
  body.only({"priority"});
  JobChange change;
  if (const auto priority = body.optional_integer("priority", 0, 100))
    change.priority = static_cast<int>(*priority);
  return change;
}

json to_json(const JobChange& change) {
  json body = json::object();
  if (change.priority) body["priority"] = *change.priority;
  return body;
}

JobSubmission JobSubmission::take(json& body) {
  JobSubmission submission = read_settings(FieldReader(body));
  submission.scene = std::move(body[JobSubmission::kSceneKey]);
  return submission;
}

JobSubmission JobSubmission::read(const FieldReader& body) {
  JobSubmission submission = read_settings(body);
  submission.scene = body.any(JobSubmission::kSceneKey);
  return submission;
}

json to_json(const JobSubmission& s) {
  json body = {{"name", s.name}, {"priority", s.priority}, {"scene", s.scene}};
  if (s.frames) body["frames"] = *s.frames;
  return body;
}

JobHealth JobHealth::read(const FieldReader& body) {
  JobHealth health;
  health.tile_failures = int_of(body, "tile_failures");
  health.refused_results = int_of(body, "refused_results");
  health.repeated_handouts = int_of(body, "repeated_handouts");
  health.last_problem = body.nullable_string("last_problem");
  health.no_progress_s = body.number("no_progress_s");
  return health;
}

json to_json(const JobHealth& h) {
  return {{"tile_failures", h.tile_failures},
          {"refused_results", h.refused_results},
          {"repeated_handouts", h.repeated_handouts},
          {"last_problem", string_or_null(h.last_problem)},
          {"no_progress_s", h.no_progress_s}};
}

JobStatus JobStatus::read(const FieldReader& body) {
  JobStatus job;
  job.id = body.string("id");
  job.name = body.string("name");
  job.state = read_job_state(body, "state");
  job.priority = int_of(body, "priority");
  job.width = int_of(body, "width");
  job.height = int_of(body, "height");
  const FieldReader tiles = body.object("tiles");
  job.tiles = {int_of(tiles, "total"), int_of(tiles, "done"), int_of(tiles, "rendering")};
  job.progress = body.number("progress");
  job.created_at = body.string("created_at");
  job.started_at = body.nullable_string("started_at");
  job.finished_at = body.nullable_string("finished_at");
  job.elapsed_s = body.number("elapsed_s");
  job.eta_s = body.nullable_number("eta_s");
  job.error = body.nullable_string("error");
  job.health = JobHealth::read(body.object("health"));
  const FieldReader stats = body.object("stats");
  job.stats = {stats.count("rays"), stats.number("rays_per_s")};
  const FieldReader frames = body.object("frames");
  job.frames.list = frames.string("list");
  job.frames.total = static_cast<int>(frames.integer("total", 1, std::numeric_limits<int>::max()));
  job.frames.done = int_of(frames, "done");
  job.frames.failed = int_of(frames, "failed");
  job.frames.failed_list = frames.string("failed_list");
  if (const auto current = frames.nullable_integer("current"))
    job.frames.current = static_cast<int>(*current);
  return job;
}

json to_json(const JobStatus& job) {
  return {
      {"id", job.id},
      {"name", job.name},
      {"state", name_in(kJobStateNames, job.state)},
      {"priority", job.priority},
      {"width", job.width},
      {"height", job.height},
      {"tiles",
       {{"total", job.tiles.total}, {"done", job.tiles.done}, {"rendering", job.tiles.rendering}}},
      {"progress", job.progress},
      {"created_at", job.created_at},
      {"started_at", string_or_null(job.started_at)},
      {"finished_at", string_or_null(job.finished_at)},
      {"elapsed_s", job.elapsed_s},
      {"eta_s", job.eta_s ? json(*job.eta_s) : json(nullptr)},
      {"error", string_or_null(job.error)},
      {"health", to_json(job.health)},
      {"stats", {{"rays", job.stats.rays}, {"rays_per_s", job.stats.rays_per_s}}},
      {"frames",
       {{"list", job.frames.list},
        {"total", job.frames.total},
        {"done", job.frames.done},
        {"failed", job.frames.failed},
        {"failed_list", job.frames.failed_list},
        {"current", job.frames.current ? json(*job.frames.current) : json(nullptr)}}}};
}

FrameStatus FrameStatus::read(const FieldReader& body) {
  FrameStatus frame;
  frame.frame = int_of(body, "frame");
  const auto state = value_in(kFrameStateNames, body.string("state"));
  if (!state) body.fail("state", "must be " + names_of(kFrameStateNames));
  frame.state = *state;
  const FieldReader tiles = body.object("tiles");
  frame.tiles = {int_of(tiles, "total"), int_of(tiles, "done"), int_of(tiles, "rendering")};
  frame.error = body.nullable_string("error");
  return frame;
}

json to_json(const FrameStatus& frame) {
  return {{"frame", frame.frame},
          {"state", name_in(kFrameStateNames, frame.state)},
          {"tiles",
           {{"total", frame.tiles.total},
            {"done", frame.tiles.done},
            {"rendering", frame.tiles.rendering}}},
          {"error", string_or_null(frame.error)}};
}

FrameList FrameList::read(const FieldReader& body) {
  return {read_array<FrameStatus>(body, "frames", &FrameStatus::read)};
}

json to_json(const FrameList& list) {
  json frames = json::array();
  for (const FrameStatus& frame : list.frames) frames.push_back(to_json(frame));
  return {{"frames", std::move(frames)}};
}

JobList JobList::read(const FieldReader& body) {
  return {read_array<JobStatus>(body, "jobs", &JobStatus::read)};
}

json to_json(const JobList& list) {
  json jobs = json::array();
  for (const JobStatus& job : list.jobs) jobs.push_back(to_json(job));
  return {{"jobs", std::move(jobs)}};
}

}  // namespace tessera::protocol
