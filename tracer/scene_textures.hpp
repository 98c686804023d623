// The textures a scene's materials read, decoded and mip-mapped once per scene, through the
// image-file module (common/image/image_file_module.hpp), which is opened only for a scene that
// has any.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "common/image/image_file_module.hpp"
#include "common/scene/scene.hpp"

namespace tessera {

class SceneTextures {
 public:
  // Throws std::runtime_error naming an image that cannot be read.
  explicit SceneTextures(const Scene& scene);

  // The index of `image` among the scene's textures: an image that several materials name
  // (the same file, or the same bytes of a model) is read once.
  std::size_t index_of(const TextureImage& image) const;
  // Only when the scene has a texture.
  const TextureSampler& sampler() const { return *sampler_; }

 private:
  std::vector<TextureImage> images_;
  std::unique_ptr<TextureSampler> sampler_;
};

}  // namespace tessera
