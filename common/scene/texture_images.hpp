// The images a scene's materials read, each once: what a worker decodes (SceneTextures) and
// what the coordinator checks at submit.
#pragma once

#include <vector>

#include "common/scene/scene.hpp"

namespace tessera {

// Whether two materials name the same image: the same file, or the same bytes of a model.
bool same_image(const TextureImage& a, const TextureImage& b);

// Every image the scene's materials name, once, in the order they first appear.
std::vector<TextureImage> texture_images(const Scene& scene);

}  // namespace tessera
