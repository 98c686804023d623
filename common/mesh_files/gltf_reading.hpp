// A glTF document tinygltf has read, made into a Model: its node hierarchy walked, its
// accessors checked against their buffers, its materials mapped. Errors name a JSON
// Pointer into the glTF.
#pragma once

#include <tiny_gltf.h>

#include "common/mesh_files/model_source.hpp"

namespace tessera {

// `images`: the bytes of each of the glTF's images, by index (null where none were read).
Model gltf_model(const tinygltf::Model& gltf, const ModelSource& source,
                 const std::vector<std::shared_ptr<const std::string>>& images = {});
Material gltf_material(const tinygltf::Material& material);

}  // namespace tessera
