// The bodies of /healthz and /readyz (a refusal of /readyz is an `Error`).
#pragma once

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"

namespace tessera::protocol {

struct Health {  // {"status": "ok"}
  static Health read(const FieldReader& body);
};
nlohmann::json to_json(const Health&);

struct Ready {  // {"status": "ready"}
  static Ready read(const FieldReader& body);
};
nlohmann::json to_json(const Ready&);

}  // namespace tessera::protocol
