// A farm job's image, or one of its frames', saved on this machine (`tessera submit -o`,
// `tessera get`).
#pragma once

#include <optional>
#include <string>

#include "common/net/coordinator_client.hpp"
#include "common/protocol/image_format.hpp"

namespace tessera {

// The format of a single image's output; fails with kExitUsage for a folder or an
// extension of no image format.
const ImageFormat& image_output_format(const std::string& output);

// The job's image, or one frame's, written to `output` whole or not at all; with
// `partial`, as far as it is rendered. An image not done yet fails with kExitJobFailed,
// saying how to get what is rendered.
void save_image(CoordinatorClient& api, const std::string& id, const std::string& output,
                bool partial, std::optional<int> frame = std::nullopt);

}  // namespace tessera
