#include "common/scene/texture_images.hpp"

#include <algorithm>

namespace tessera {

bool same_image(const TextureImage& a, const TextureImage& b) {
  return a.bytes ? a.bytes == b.bytes : !b.bytes && a.path == b.path;
}

std::vector<TextureImage> texture_images(const Scene& scene) {
  std::vector<TextureImage> images;
  for (const Material& material : scene.materials)
    for (const auto& texture : material.textures)
      if (texture && std::none_of(images.begin(), images.end(), [&](const TextureImage& known) {
            return same_image(known, texture->image);
          }))
        images.push_back(texture->image);
  return images;
}

}  // namespace tessera
