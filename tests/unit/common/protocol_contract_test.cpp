// The contract between common/protocol and docs/openapi.yaml, read with yaml-cpp: each body
// of the file is one C++ type, and the type's JSON has exactly the schema's properties, its
// reader requires exactly the schema's required fields, takes null exactly where the schema
// says nullable, keeps to the schema's integer bounds, string lengths and enum values.
// Everything about the type is learned from its behaviour (to_json of a full instance,
// T::read of variations of it), so nothing here lists a field a second time.
#include <functional>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "common/protocol/assets.hpp"
#include "common/protocol/error.hpp"
#include "common/protocol/events.hpp"
#include "common/protocol/health.hpp"
#include "common/protocol/image_format.hpp"
#include "common/protocol/jobs.hpp"
#include "common/protocol/leases.hpp"
#include "common/protocol/paths.hpp"
#include "common/protocol/workers.hpp"

namespace tessera::protocol {
namespace {

using nlohmann::json;
using Reader = std::function<void(const json&)>;

template <typename T>
Reader reader_of() {
  return [](const json& body) { T::read(FieldReader(body)); };
}

bool reads(const Reader& read, const json& body) {
  try {
    read(body);
    return true;
  } catch (const ProtocolError&) {
    return false;
  }
}

class OpenApi {
 public:
  OpenApi() : root_(YAML::LoadFile(std::string(TESSERA_SOURCE_DIR) + "/docs/openapi.yaml")) {}

  // A schema, with a $ref followed.
  YAML::Node resolve(YAML::Node node) const {
    while (node["$ref"]) {
      const std::string ref = node["$ref"].as<std::string>();  // "#/components/schemas/X"
      node = root_["components"]["schemas"][ref.substr(ref.rfind('/') + 1)];
    }
    return node;
  }
  YAML::Node schema(const std::string& name) const {
    return resolve(root_["components"]["schemas"][name]);
  }
  YAML::Node operation(const std::string& path, const std::string& method) const {
    return root_["paths"][path][method];
  }
  YAML::Node response(const std::string& path, const std::string& method,
                      const std::string& status) const {
    return resolve(
        operation(path, method)["responses"][status]["content"]["application/json"]["schema"]);
  }
  YAML::Node request(const std::string& path, const std::string& method) const {
    return resolve(operation(path, method)["requestBody"]["content"]["application/json"]["schema"]);
  }
  const YAML::Node& root() const { return root_; }

 private:
  YAML::Node root_;
};

std::set<std::string> names(const YAML::Node& list) {
  std::set<std::string> out;
  if (!list) return out;
  for (const auto& item : list) out.insert(item.as<std::string>());
  return out;
}

// Compares the object at `pointer` in `sample` with `schema`, reading variations of the
// whole sample with `read`.
void check_object(const OpenApi& api, const YAML::Node& schema, const json& sample,
                  const json::json_pointer& pointer, const Reader& read) {
  SCOPED_TRACE("at " + (pointer.empty() ? std::string("the body") : pointer.to_string()));
  const json& object = sample.at(pointer);
  ASSERT_TRUE(object.is_object());
  ASSERT_TRUE(schema["properties"]) << "the schema has no properties";
  std::set<std::string> documented;
  for (const auto& property : schema["properties"])
    documented.insert(property.first.as<std::string>());
  std::set<std::string> written;
  for (const auto& [key, value] : object.items()) written.insert(key);
  EXPECT_EQ(written, documented) << "the type's JSON and the schema's properties differ";

  const std::set<std::string> required = names(schema["required"]);
  for (const std::string& key : documented) {
    if (!object.contains(key)) continue;
    SCOPED_TRACE("property " + key);
    const json::json_pointer at = pointer / key;
    const YAML::Node property = api.resolve(schema["properties"][key]);
    json without = sample;
    without.at(pointer).erase(key);
    EXPECT_EQ(!reads(read, without), required.contains(key)) << "required differs";
    json null = sample;
    null[at] = nullptr;
    const bool nullable = property["nullable"] && property["nullable"].as<bool>();
    EXPECT_EQ(reads(read, null), nullable) << "nullable differs";

    const std::string type = property["type"] ? property["type"].as<std::string>() : "";
    const json& value = sample[at];
    if (type == "integer") {
      EXPECT_TRUE(value.is_number_integer());
    } else if (type == "number") {
      EXPECT_TRUE(value.is_number());
    } else if (type == "string") {
      EXPECT_TRUE(value.is_string());
    }
    if (type == "object") {
      EXPECT_TRUE(value.is_object());
      if (property["properties"]) check_object(api, property, sample, at, read);
    }
    if (type == "array") {
      ASSERT_TRUE(value.is_array() && !value.empty()) << "the sample needs one item";
      const YAML::Node items = api.resolve(property["items"]);
      if (items["properties"]) check_object(api, items, sample, at / 0, read);
    }
    if (type == "integer" && property["minimum"]) {
      json below = sample;
      below[at] = property["minimum"].as<long long>() - 1;
      EXPECT_FALSE(reads(read, below)) << "below the minimum reads";
    }
    if (type == "integer" && property["maximum"]) {
      json above = sample;
      above[at] = property["maximum"].as<long long>() + 1;
      EXPECT_FALSE(reads(read, above)) << "above the maximum reads";
    }
    if (type == "string" && property["maxLength"]) {
      json longer = sample;
      longer[at] = std::string(property["maxLength"].as<std::size_t>() + 1, 'x');
      EXPECT_FALSE(reads(read, longer)) << "longer than maxLength reads";
    }
    if (property["enum"]) {
      for (const auto& allowed : property["enum"]) {
        json with = sample;
        if (type == "integer")
          with[at] = allowed.as<long long>();
        else
          with[at] = allowed.as<std::string>();
        EXPECT_TRUE(reads(read, with)) << allowed.as<std::string>() << " is in the enum";
      }
      json other = sample;
      if (type == "integer")
        other[at] = property["enum"][0].as<long long>() + 1;
      else
        other[at] = "not-a-value";
      EXPECT_FALSE(reads(read, other)) << "a value outside the enum reads";
    }
  }
}

template <typename T>
void check(const OpenApi& api, const YAML::Node& schema, const T& full) {
  ASSERT_TRUE(schema.IsDefined() && schema.IsMap()) << "no such schema";
  const json sample = to_json(full);
  ASSERT_TRUE(reads(reader_of<T>(), sample)) << "a full " << sample.dump() << " does not read";
  check_object(api, schema, sample, json::json_pointer(), reader_of<T>());
}

JobStatus full_job() {
  JobStatus job;
  job.id = "j-1";
  job.name = "a";
  job.state = JobState::running;
  job.tiles = {4, 2, 1};
  job.progress = 0.5;
  job.created_at = "2026-12-04T20:00:00.000Z";
  job.started_at = job.created_at;
  job.finished_at = job.created_at;
  job.eta_s = 1.5;
  job.error = "none";
  job.health.last_problem = "none";
  job.stats = {1000, 2.5};
  job.frames = {"1-4", 4, 1, 1, "3", 2};
  return job;
}

FrameStatus full_frame() { return {3, FrameState::failed, {4, 1, 0}, "tile 2 failed"}; }

Worker full_worker() {
  Worker worker{
      "w-1", "a", "h", 2, WorkerState::rendering, "j-1", 3, 7, "2026-12-04T20:00:00.000Z"};
  worker.draining = true;
  worker.tiles_per_min = 12;
  worker.rays_per_s = 1.5e6;
  return worker;
}

TileStatus full_tile() {
  TileStatus tile{3, 1, 16, 32, 16, 8, TileView::done, "w-1", "a", 12.5, "AAAA"};
  return tile;
}

// The schema of an event's data, from the stream's x-tessera-event-data.
YAML::Node event_data(const OpenApi& api, const std::string& path, const std::string& type) {
  return api.operation(
      path,
      "get")["responses"]["200"]["content"]["text/event-stream"]["x-tessera-event-data"][type];
}

TEST(ProtocolContractTest, EveryBodyIsItsSchema) {
  const OpenApi api;
  check(api, api.schema("Error"),
        Error{"over_limit", "too many", "/scene/objects", "max_objects", 10});
  check(api, api.schema("JobSubmission"), JobSubmission{"a", 60, json{{"version", 1}}, "1-48x2"});
  check(api, api.schema("JobStatus"), full_job());
  check(api, api.request("/v1/jobs/{id}", "patch"), JobChange{70});
  check(api, api.response("/v1/jobs", "get", "200"), JobList{{full_job()}});
  check(api, api.schema("Worker"), full_worker());
  check(api, api.response("/v1/workers", "get", "200"), WorkerList{{full_worker()}});
  check(api, api.request("/v1/workers", "post"), WorkerRegistration{"a", "h", 4});
  check(api, api.schema("Registration"),
        Registration{"w-1", "0123abcd", 5, 30, kWorkerProtocolVersion, {}});
  check(api, api.schema("Lease"), Lease{"l-1", "j-1", "abc", 7, {{3, 0, 8, 8, 8}}, 29.5});
  check(api, api.request("/v1/leases/{id}/fail", "post"), TileFailure{3, "broke"});
  check(api, api.response("/v1/leases/{id}/result", "put", "200"), ResultAnswer{});
  check(api, api.response("/healthz", "get", "200"), Health{});
  check(api, api.response("/readyz", "get", "200"), Ready{});
  check(api, api.schema("AssetStored"), AssetStored{"sha256:" + std::string(64, 'a'), true});
  check(api, api.schema("TileStatus"), full_tile());
  check(api, api.schema("FrameStatus"), full_frame());
  check(api, api.response("/v1/jobs/{id}/frames", "get", "200"), FrameList{{full_frame()}});
  check(api, api.response("/v1/jobs/{id}/tiles", "get", "200"), TileList{{full_tile()}, 2, 1});
  check(api, event_data(api, "/v1/events", "worker"),
        WorkerEvent{WorkerChange::joined, full_worker()});
  check(api, event_data(api, "/v1/events", "resync"), Resync{"fell behind"});
  check(api, event_data(api, "/v1/events", "job_removed"), JobRemoved{"j-1"});
  check(api, event_data(api, "/v1/jobs/{id}/events", "resync"), Resync{"fell behind"});
  check(api, event_data(api, "/v1/jobs/{id}/events", "job_removed"), JobRemoved{"j-1"});
  EXPECT_EQ(api.resolve(event_data(api, "/v1/events", "job"))["required"].size(),
            api.schema("JobStatus")["required"].size());
  EXPECT_EQ(api.resolve(event_data(api, "/v1/jobs/{id}/events", "tile"))["required"].size(),
            api.schema("TileStatus")["required"].size());
}

// The coordinator refuses an unknown submission key before building its value, from
// JobSubmission::kKeys: those are the schema's properties, and a reader names them.
TEST(ProtocolContractTest, TheSubmissionsKeysAreItsSchemasProperties) {
  const OpenApi api;
  std::set<std::string> properties;
  for (const auto& property : api.schema("JobSubmission")["properties"])
    properties.insert(property.first.as<std::string>());
  const std::set<std::string> keys(std::begin(JobSubmission::kKeys),
                                   std::end(JobSubmission::kKeys));
  EXPECT_EQ(keys, properties);
  try {
    JobSubmission::read(FieldReader(json{{"scene", json::object()}, {"nmae", "a"}}));
    ADD_FAILURE() << "an unknown key was taken";
  } catch (const ProtocolError& e) {
    EXPECT_EQ(e.pointer(), "/nmae");
    EXPECT_NE(std::string(e.what()).find("expected name, priority, frames, scene"),
              std::string::npos)
        << e.what();
  }
}

TEST(ProtocolContractTest, EnumsAreTheSchemasEnums) {
  const OpenApi api;
  std::set<std::string> states;
  for (const auto& [state, name] : kJobStateNames) states.insert(std::string(name));
  EXPECT_EQ(states, names(api.schema("JobState")["enum"]));
  std::set<std::string> worker_states;
  for (const auto& [state, name] : kWorkerStateNames) worker_states.insert(std::string(name));
  EXPECT_EQ(worker_states, names(api.schema("Worker")["properties"]["state"]["enum"]));
  std::set<std::string> tile_views;
  for (const auto& [view, name] : kTileViewNames) tile_views.insert(std::string(name));
  EXPECT_EQ(tile_views, names(api.schema("TileStatus")["properties"]["state"]["enum"]));
  std::set<std::string> frame_states;
  for (const auto& [state, name] : kFrameStateNames) frame_states.insert(std::string(name));
  EXPECT_EQ(frame_states, names(api.schema("FrameStatus")["properties"]["state"]["enum"]));
  std::set<std::string> changes;
  for (const auto& [change, name] : kWorkerChangeNames) changes.insert(std::string(name));
  EXPECT_EQ(changes,
            names(event_data(api, "/v1/events", "worker")["properties"]["change"]["enum"]));
  std::set<std::string> formats;
  for (const ImageFormat& format : kImageFormats) formats.insert(std::string(format.name));
  std::set<std::string> documented;
  for (const auto& parameter : api.operation("/v1/jobs/{id}/image", "get")["parameters"]) {
    if (parameter["name"].as<std::string>() == query::format)
      documented = names(parameter["schema"]["enum"]);
  }
  EXPECT_EQ(formats, documented);
  std::set<std::string> content_types;
  for (const ImageFormat& format : kImageFormats)
    content_types.insert(std::string(format.content_type));
  std::set<std::string> served;
  for (const auto& type :
       api.operation("/v1/jobs/{id}/image", "get")["responses"]["200"]["content"])
    served.insert(type.first.as<std::string>());
  EXPECT_EQ(content_types, served);
}

TEST(ProtocolContractTest, EveryRouteIsThePathsOfTheFile) {
  const OpenApi api;
  std::set<std::string> documented;
  for (const auto& path : api.root()["paths"]) documented.insert(path.first.as<std::string>());
  std::set<std::string> named;
  for (const std::string_view route : route::all) named.insert(std::string(route));
  EXPECT_EQ(named, documented);
  for (const auto& path : api.root()["paths"]) {
    for (const auto& method : path.second) {
      if (!method.second.IsMap()) continue;  // a path's own parameters
      for (const auto& parameter : method.second["parameters"]) {
        if (!parameter["in"] || parameter["in"].as<std::string>() != "header") continue;
        const std::string name = parameter["name"].as<std::string>();
        EXPECT_TRUE(name == kTilesHeader || name == kRaysHeader ||
                    name == kRenderMicrosecondsHeader || name == kLastEventIdHeader)
            << name;
      }
    }
  }
}

TEST(ProtocolContractTest, IdsArePercentEncodedIntoTheirSegment) {
  EXPECT_EQ(fill(route::job, "j-1"), "/v1/jobs/j-1");
  EXPECT_EQ(fill(route::job_cancel, "../x y"), "/v1/jobs/..%2Fx%20y/cancel");
  EXPECT_EQ(frame_image_target("../x", 12, *image_format_named("exr"), true),
            "/v1/jobs/..%2Fx/frames/12/image?format=exr&partial=1");
  EXPECT_EQ(claim_target("w 1", 10, 4), "/v1/workers/w%201/claim?wait_s=10&max_tiles=4");
  EXPECT_EQ(job_target("j", 0.5), "/v1/jobs/j?wait_s=0.5");
  EXPECT_EQ(jobs_target(JobState::failed, 20), "/v1/jobs?limit=20&state=failed");
}

TEST(ProtocolContractTest, AReaderSaysWhereAndWhat) {
  try {
    read_body<JobStatus>(R"({"id": 3})");
    FAIL() << "read";
  } catch (const ProtocolError& e) {
    EXPECT_EQ(e.pointer(), "/id");
    EXPECT_EQ(e.message(), "must be a string, got integer");
  }
  try {
    read_body<Lease>(
        R"({"id": "l", "job_id": "j", "scene_digest": "d", "frame": 0, "expires_in_s": 1,
                         "tiles": [{"index": 0, "x": 0, "y": 0, "width": 8, "height": 8}, {}]})");
    FAIL() << "read";
  } catch (const ProtocolError& e) {
    EXPECT_EQ(e.pointer(), "/tiles/1/index");
    EXPECT_EQ(e.message(), "is required");
  }
  EXPECT_THROW(read_body<Health>("not json"), ProtocolError);
  EXPECT_EQ(error_message(502, "<html>bad gateway</html>"), "HTTP 502: <html>bad gateway</html>");
  EXPECT_EQ(error_message(404, R"({"error": {"code": "not_found", "message": "no job x"}})"),
            "no job x");
}

}  // namespace
}  // namespace tessera::protocol
