#include "common/protocol/workers.hpp"

#include "common/protocol/jobs.hpp"

namespace tessera::protocol {
namespace {

using nlohmann::json;

// The version the other side states: anything but this build's is a mismatch. Said from
// the side that reads it, the coordinator's or the worker's.
enum class Reader { coordinator, worker };
void check_version(const FieldReader& body, Reader reader) {
  const bool stated = body.has("protocol");
  const json& version = stated ? body.any("protocol") : json();
  if (version.is_number_integer() && version == kWorkerProtocolVersion) return;
  const std::string ours = std::to_string(kWorkerProtocolVersion);
  const std::string theirs = version.dump().substr(0, 40);
  if (reader == Reader::coordinator)
    throw ProtocolMismatch(
        body.pointer("protocol"),
        "this coordinator speaks worker protocol " + ours + "; the worker " +
            (stated ? "speaks " + theirs : "states none (a build older than protocol 2)") +
            ". Run the same Tessera release on the coordinator and its workers");
  throw ProtocolMismatch(body.pointer("protocol"), "the coordinator speaks worker protocol " +
                                                       (stated ? theirs : "1 (it states none)") +
                                                       ", this worker " + ours +
                                                       ": run the same Tessera release on both");
}

}  // namespace

WorkerRegistration WorkerRegistration::read(const FieldReader& body) {
  WorkerRegistration registration;
  registration.name = read_name(body, "name");
  if (body.has("host")) registration.host = read_name(body, "host");
  if (const auto threads = body.optional_integer("threads", 1, 1 << 20))
    registration.threads = static_cast<int>(*threads);
  check_version(body, Reader::coordinator);
  return registration;
}

json to_json(const WorkerRegistration& r) {
  json body = {{"name", r.name}, {"protocol", r.protocol}};
  if (r.host) body["host"] = *r.host;
  if (r.threads) body["threads"] = *r.threads;
  return body;
}

Registration Registration::read(const FieldReader& body) {
  check_version(body, Reader::worker);
  Registration registration;
  registration.id = body.string("id");
  registration.secret = body.string("secret");
  registration.heartbeat_interval_s = body.number("heartbeat_interval_s");
  registration.lease_timeout_s = body.number("lease_timeout_s");
  registration.limits = read_limits(body.object("limits"));
  return registration;
}

json to_json(const Registration& r) {
  return {{"id", r.id},
          {"secret", r.secret},
          {"heartbeat_interval_s", r.heartbeat_interval_s},
          {"lease_timeout_s", r.lease_timeout_s},
          {"protocol", r.protocol},
          {"limits", to_json(r.limits)}};
}

Worker Worker::read(const FieldReader& body) {
  Worker worker;
  worker.id = body.string("id");
  worker.name = body.string("name");
  worker.host = body.string("host");
  worker.threads = static_cast<int>(body.integer("threads", 1, 1 << 20));
  const auto state = value_in(kWorkerStateNames, body.string("state"));
  if (!state) body.fail("state", "must be " + names_of(kWorkerStateNames));
  worker.state = *state;
  worker.current_job = body.nullable_string("current_job");
  if (const auto tile = body.nullable_integer("current_tile"))
    worker.current_tile = static_cast<int>(*tile);
  worker.tiles_rendered = body.count("tiles_rendered");
  worker.last_seen = body.string("last_seen");
  worker.draining = body.boolean("draining");
  worker.tiles_per_min = body.number("tiles_per_min");
  worker.rays_per_s = body.number("rays_per_s");
  return worker;
}

json to_json(const Worker& w) {
  return {{"id", w.id},
          {"name", w.name},
          {"host", w.host},
          {"threads", w.threads},
          {"state", name_in(kWorkerStateNames, w.state)},
          {"current_job", w.current_job ? json(*w.current_job) : json(nullptr)},
          {"current_tile", w.current_tile ? json(*w.current_tile) : json(nullptr)},
          {"tiles_rendered", w.tiles_rendered},
          {"last_seen", w.last_seen},
          {"draining", w.draining},
          {"tiles_per_min", w.tiles_per_min},
          {"rays_per_s", w.rays_per_s}};
}

WorkerList WorkerList::read(const FieldReader& body) {
  return {read_array<Worker>(body, "workers", &Worker::read)};
}

json to_json(const WorkerList& list) {
  json workers = json::array();
  for (const Worker& worker : list.workers) workers.push_back(to_json(worker));
  return {{"workers", std::move(workers)}};
}

}  // namespace tessera::protocol
