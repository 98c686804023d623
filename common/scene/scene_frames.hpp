// The frames of one scene's text: read in full once, then frame by frame, reading again only
// what the animation changes.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "common/scene/scene.hpp"
#include "common/scene/scene_files.hpp"

namespace tessera {

class SceneFrames {
 public:
  // Reads and checks the scene as parse_scene_text() does (every frame of every track
  // included): a SceneError for any mistake. `edit` as there; `files` outlives this.
  SceneFrames(std::string text, const Limits& limits,
              std::function<void(nlohmann::json&)> edit = {}, const SceneFiles* files = nullptr);

  const Animation& animation() const { return animation_; }
  // The scene at its first frame, as read in full; once.
  Scene take_first() { return std::move(first_); }
  // The scene at `frame`, made from `previous`, the scene of another frame of this text
  // (such as a Renderer keeps it, its meshes perhaps released): only the camera, lights,
  // background and named materials are read again, unless tracks lie in the objects, when
  // the whole text is. A frame outside the range is a SceneError.
  Scene at(int frame, Scene previous) const;

 private:
  Limits limits_;
  std::function<void(nlohmann::json&)> edit_;
  const SceneFiles* files_;
  Animation animation_;
  Scene first_;
  nlohmann::json parts_;  // the members advance_scene() reads again
  std::string text_;      // only when the objects hold tracks
};

}  // namespace tessera
