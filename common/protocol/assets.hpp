// The answer to an asset upload (PUT /v1/assets/{digest}).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "common/protocol/field_reader.hpp"

namespace tessera::protocol {

struct AssetStored {
  std::string digest;  // "sha256:" and 64 hex digits
  bool added = false;  // false: the coordinator held it already
  static AssetStored read(const FieldReader& body);
};
nlohmann::json to_json(const AssetStored& stored);

}  // namespace tessera::protocol
