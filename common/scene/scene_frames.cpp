#include "common/scene/scene_frames.hpp"

#include <string_view>
#include <utility>

#include "common/scene/scene_parser.hpp"

namespace tessera {

SceneFrames::SceneFrames(std::string text, const Limits& limits,
                         std::function<void(nlohmann::json&)> edit, const SceneFiles* files)
    : limits_(limits), edit_(std::move(edit)), files_(files) {
  // The small members are kept as the reading meets them, so that the text (a mesh's
  // millions of numbers) is parsed once.
  const auto keep_parts = [this](nlohmann::json& document) {
    if (edit_) edit_(document);
    if (!document.is_object() || !document.contains("animation")) return;
    for (const std::string_view key :
         {"animation", "camera", "lights", "materials", "background", "ambient_light"}) {
      if (const auto found = document.find(key); found != document.end())
        parts_[std::string(key)] = *found;
    }
  };
  first_ = parse_scene_text(text, limits_, keep_parts, files_);
  animation_ = first_.animation;
  if (animation_.changes_objects()) text_ = std::move(text);
}

Scene SceneFrames::at(int frame, Scene previous) const {
  if (animation_.changes_objects()) return parse_scene_text(text_, limits_, edit_, files_, frame);
  if (!animation_.animated) {
    if (frame != 0)
      throw SceneError("", "has no frame " + std::to_string(frame) +
                               ": a scene without \"animation\" is the one frame 0");
    return previous;
  }
  return advance_scene(parts_, std::move(previous), frame, limits_, files_);
}

}  // namespace tessera
