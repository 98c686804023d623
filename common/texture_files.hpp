// Inside the image-file module only (image_file_module.hpp): textures through OpenImageIO.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "common/image_file_module.hpp"

namespace tessera {

std::unique_ptr<TextureSampler> open_textures(const std::vector<TextureImage>& images);
std::uint64_t check_texture(const TextureImage& image);

}  // namespace tessera
