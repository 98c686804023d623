// A scene's output transfer in words: in the scene format (render.output_transfer) and in
// the coordinator's job rows.
#pragma once

#include <string_view>

#include "common/scene/scene.hpp"

namespace tessera {

// By the enum's value: srgb, linear.
inline constexpr std::string_view kOutputTransferNames[] = {"srgb", "linear"};

inline std::string_view output_transfer_name(OutputTransfer transfer) {
  return kOutputTransferNames[static_cast<int>(transfer)];
}

// Anything but "linear" is sRGB, the default.
inline OutputTransfer output_transfer_named(std::string_view name) {
  return name == output_transfer_name(OutputTransfer::linear) ? OutputTransfer::linear
                                                              : OutputTransfer::srgb;
}

}  // namespace tessera
