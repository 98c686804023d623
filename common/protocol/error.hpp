// The body of every error answer (`Error`): {"error": {"code", "message", "path"?, ...}}.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"

namespace tessera::protocol {

struct Error {
  std::string code;     // machine-readable: invalid_scene, not_found, lease_lost, ...
  std::string message;  // for people
  // A JSON Pointer into the request body, for errors about one of its values.
  std::optional<std::string> path;
  // For over_limit: the coordinator's limit that the request crossed, and its value.
  std::optional<std::string> limit;
  std::optional<std::uint64_t> limit_value;

  static Error read(const FieldReader& body);
};
nlohmann::json to_json(const Error& error);

// The error of an answer's body, or nothing when the body is not an `Error`.
std::optional<Error> error_of(std::string_view body);
// What an error answer says, for people: its message, or, from something other than the
// coordinator (a proxy, say), "HTTP 502: " and the start of its body.
std::string error_message(int status, std::string_view body);

}  // namespace tessera::protocol
