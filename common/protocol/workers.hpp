// The bodies of /v1/workers: a worker's registration and its answer, and the workers list.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"
#include "common/protocol/limits.hpp"
#include "common/protocol/names.hpp"

namespace tessera::protocol {

// The other side speaks another version of the worker protocol (or states none, as builds
// before version 2 did). The coordinator answers 409 protocol_mismatch; a worker stops.
class ProtocolMismatch : public ProtocolError {
 public:
  using ProtocolError::ProtocolError;
};

// POST /v1/workers: a worker introduces itself.
struct WorkerRegistration {
  std::string name;
  std::optional<std::string> host;  // the coordinator takes the peer's address without it
  std::optional<int> threads;
  int protocol = kWorkerProtocolVersion;

  // Throws ProtocolMismatch for another version, once the rest has been read.
  static WorkerRegistration read(const FieldReader& body);
};
nlohmann::json to_json(const WorkerRegistration& registration);

// Every call a worker makes after registering sends the secret of its Registration in this
// header: the worker token says a caller may be a worker, the secret which one it is.
inline constexpr std::string_view kWorkerSecretHeader = "X-Tessera-Worker-Secret";

// Its answer (`Registration`).
struct Registration {
  std::string id;
  std::string secret;  // given once, here; the coordinator keeps only its digest
  double heartbeat_interval_s = 5;
  double lease_timeout_s = 30;
  int protocol = kWorkerProtocolVersion;
  ProtocolLimits limits;

  // Throws ProtocolMismatch for a coordinator of another version.
  static Registration read(const FieldReader& body);
};
nlohmann::json to_json(const Registration& registration);

// gone: not heard from (it may come back, and claim again); left: it said goodbye, and must
// register again before it claims.
enum class WorkerState { idle, rendering, gone, left };
inline constexpr NameTable<WorkerState, 4> kWorkerStateNames{{
    {WorkerState::idle, "idle"},
    {WorkerState::rendering, "rendering"},
    {WorkerState::gone, "gone"},
    {WorkerState::left, "left"},
}};
inline const char* to_string(WorkerState state) { return name_in(kWorkerStateNames, state).data(); }

// One worker of GET /v1/workers (`Worker`).
struct Worker {
  std::string id;
  std::string name;
  std::string host;
  int threads = 1;
  WorkerState state = WorkerState::idle;
  std::optional<std::string> current_job;
  std::optional<int> current_tile;
  std::uint64_t tiles_rendered = 0;
  std::string last_seen;     // RFC 3339 (timestamp.hpp)
  bool draining = false;     // takes no more tiles once its lease is done
  double tiles_per_min = 0;  // over the last minute
  double rays_per_s = 0;     // over the last minute

  static Worker read(const FieldReader& body);
};
nlohmann::json to_json(const Worker& worker);

struct WorkerList {
  std::vector<Worker> workers;

  static WorkerList read(const FieldReader& body);
};
nlohmann::json to_json(const WorkerList& list);

}  // namespace tessera::protocol
