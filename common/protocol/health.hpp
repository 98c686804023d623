// The bodies of /healthz and /readyz (a refusal of /readyz is an `Error`).
#pragma once

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"

namespace tessera::protocol {

struct Health {  // {"status": "ok", "api_token_required": false}
  // Whether the client routes want the API token: a web page asks for it before any call
  // rather than after a refusal. What a 401 would say anyway, told to anyone.
  bool api_token_required = false;
  static Health read(const FieldReader& body);
};
nlohmann::json to_json(const Health&);

struct Ready {  // {"status": "ready"}
  static Ready read(const FieldReader& body);
};
nlohmann::json to_json(const Ready&);

}  // namespace tessera::protocol
