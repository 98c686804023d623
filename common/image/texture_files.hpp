// Inside the image-file module only (image_file_module.hpp): textures through OpenImageIO.
#pragma once

#include <memory>
#include <vector>

#include "common/image/image_file_module.hpp"

namespace tessera {

std::unique_ptr<TextureSampler> open_textures(const std::vector<TextureImage>& images);
void check_textures(const std::vector<TextureImage>& images);

}  // namespace tessera
