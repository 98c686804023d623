#include "common/protocol/assets.hpp"

namespace tessera::protocol {

AssetStored AssetStored::read(const FieldReader& body) {
  body.only({"digest", "added"});
  AssetStored stored;
  stored.digest = body.string("digest");
  const nlohmann::json& added = body.any("added");
  if (!added.is_boolean()) body.fail("added", "must be a boolean");
  stored.added = added.get<bool>();
  return stored;
}

nlohmann::json to_json(const AssetStored& stored) {
  return {{"digest", stored.digest}, {"added", stored.added}};
}

}  // namespace tessera::protocol
