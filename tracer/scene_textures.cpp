#include "tracer/scene_textures.hpp"

#include <algorithm>
#include <stdexcept>

#include "common/image/image_file_loader.hpp"
#include "common/scene/texture_images.hpp"

namespace tessera {

SceneTextures::SceneTextures(const Scene& scene) : images_(texture_images(scene)) {
  if (!images_.empty()) sampler_ = image_files().open_textures(images_);
}

std::size_t SceneTextures::index_of(const TextureImage& image) const {
  const auto found = std::find_if(images_.begin(), images_.end(), [&](const TextureImage& known) {
    return same_image(known, image);
  });
  if (found == images_.end()) throw std::logic_error("a texture the scene's materials do not name");
  return static_cast<std::size_t>(found - images_.begin());
}

}  // namespace tessera
