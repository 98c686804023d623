// What `tessera submit` does for a scene that names mesh files: each file, and every file
// it names (an MTL, a texture, a .bin), goes to the coordinator as an asset unless it is
// there already, and the scene then names them by digest (docs/scene-format.md, "Mesh
// files on the farm").
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "common/net/coordinator_client.hpp"

namespace tessera {

struct AssetUploads {
  std::size_t uploaded = 0;  // sent, new to the coordinator
  std::size_t held = 0;      // already there: not sent
  std::uint64_t bytes = 0;   // of those sent
};

// Rewrites each {"type": "mesh", "file": F} of `scene` (F relative to `folder`) to the
// farm's form, sending what the coordinator lacks; progress lines go to `progress`. Throws
// SceneFileError for a file that cannot be read, ApiError and HttpError as the client does.
AssetUploads send_scene_assets(nlohmann::json& scene, const std::filesystem::path& folder,
                               CoordinatorClient& api, std::FILE* progress);

}  // namespace tessera
