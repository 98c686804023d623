// What one request of the worker protocol may carry, named once for both sides. The
// coordinator states its limits when a worker registers (POST /v1/workers) and the worker
// keeps to them; a worker and a coordinator that speak different versions of the protocol
// refuse each other there, clearly, instead of meeting later as refused results.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "common/protocol/field_reader.hpp"

namespace tessera {

// The version of the worker protocol this build speaks. Raised whenever a worker of one
// build could misread a coordinator of another: version 2 states the limits below at
// registration; version 1 left them to constants written on each side. Version 3 gives
// each worker a secret at registration that its later calls send (kWorkerSecretHeader).
// Version 4 names the frame a lease's tiles belong to (an older worker would render every
// frame of an animation as its first).
inline constexpr int kWorkerProtocolVersion = 4;

struct ProtocolLimits {
  // Tiles one result (PUT /v1/leases/{id}/result) may name in X-Tessera-Tiles.
  int max_result_tiles = 256;
  // Bytes of pixels one result may carry; never less than one tile of the largest size a
  // scene may ask for, so that any tile fits in a result of its own.
  std::size_t max_result_bytes = std::size_t{64} << 20;
  // Tiles one claim or one extension may hand out (their max_tiles parameter).
  int max_batch_tiles = 256;
  // Tiles a lease may owe at once: an extension adds no more than what keeps it within.
  int max_lease_tiles = 1024;

  bool operator==(const ProtocolLimits&) const = default;
};

// The coordinator's limits for scenes whose tiles are at most `max_tile_size` pixels wide.
ProtocolLimits coordinator_limits(int max_tile_size);

namespace protocol {
// As stated in the registration's answer (`Limits`): {"max_result_tiles": ..., ...}.
nlohmann::json to_json(const ProtocolLimits& limits);
// Each limit must be there, and a whole number of at least 1: a coordinator that states 0
// or nothing is not one a worker can keep to. Throws ProtocolError.
ProtocolLimits read_limits(const FieldReader& limits);
}  // namespace protocol

// "1365" -> "1,365": counts in messages people read.
std::string with_thousands(std::uint64_t n);

// The coordinator's answer to a result over a limit, for example "a result carries at most
// 256 tiles; this one has 1,365".
std::string result_tiles_over_limit(const ProtocolLimits& limits, std::uint64_t tiles);

}  // namespace tessera
