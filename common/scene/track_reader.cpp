// Reading a keyframe track where a scene's value belongs (ValueReader::animated()).
#include <string>

#include "common/scene/scene_parser_parts.hpp"
#include "common/scene/value_reader.hpp"

namespace tessera {
namespace {

using nlohmann::json;

TrackTarget target_of(std::string_view pointer) {
  if (pointer.starts_with("/camera/")) return TrackTarget::camera;
  if (pointer.starts_with("/lights/")) return TrackTarget::light;
  if (pointer.starts_with("/materials/")) return TrackTarget::named_material;
  if (pointer.starts_with("/objects/")) return TrackTarget::object;
  return TrackTarget::background;
}

json value_json(const std::array<double, 3>& value, int size) {
  if (size == 1) return value[0];
  return json::array({value[0], value[1], value[2]});
}

}  // namespace

ValueReader ValueReader::at(const FrameReading& frames) const {
  ValueReader copy = *this;
  copy.frames_ = &frames;
  return copy;
}

Track ValueReader::read_track(const std::function<void(const ValueReader&)>& check,
                              bool bounded) const {
  const Animation& animation = *frames_->animation;
  const ObjectReader reader(*this, "a keyframe track");
  reader.allow_only({"keys", "interpolation"});
  Track track;
  track.pointer = pointer_;
  track.target = target_of(pointer_);
  track.bounded = bounded;
  if (const auto interpolation = reader.find("interpolation"))
    track.interpolation = enum_choice<Interpolation>(*interpolation, interpolation_names);
  const ValueReader keys = reader.require("keys");
  const std::size_t count = keys.array_size("an array of keys [frame, value]");
  if (count == 0) keys.fail("must hold at least one key [frame, value]");
  // Frames strictly increase inside the range, so no more keys than frames fit.
  if (static_cast<std::int64_t>(count) > animation.frame_count()) {
    keys.fail("must have at most one key per frame of the animation (" +
              std::to_string(animation.frame_count()) + "), got " + std::to_string(count));
  }
  const std::string range_reason = "the animation's frames are " + std::to_string(animation.first) +
                                   " to " + std::to_string(animation.last);
  track.keys.reserve(count);
  for (std::size_t k = 0; k < count; ++k) {
    const ValueReader key = keys.element(k);
    key.expect_array_of(2, "a key [frame, value]");
    const ValueReader frame = key.element(0);
    TrackKey parsed;
    parsed.frame = static_cast<int>(frame.integer({animation.first, animation.last, range_reason}));
    if (k > 0 && parsed.frame <= track.keys.back().frame) {
      frame.fail("must be after the frame of the key before it (" +
                 std::to_string(track.keys.back().frame) + "), got " +
                 std::to_string(parsed.frame));
    }
    const ValueReader value = key.element(1);
    check(value);
    if (value.json().is_number()) {
      parsed.value.fill(value.json().get<double>());
    } else {
      for (std::size_t c = 0; c < 3; ++c) parsed.value[c] = value.json()[c].get<double>();
      track.size = 3;
    }
    track.keys.push_back(parsed);
  }
  return track;
}

ValueReader ValueReader::track_at_frame(const std::function<void(const ValueReader&)>& check,
                                        bool bounded) const {
  if (frames_ == nullptr || frames_->animation == nullptr || !frames_->animation->animated) {
    fail(
        "is a keyframe track, but the scene is not animated: give it \"animation\": "
        "{\"frames\": [first, last]}");
  }
  ValueReader out = *this;
  const Track* known = nullptr;
  if (frames_->known != nullptr) {
    if (const auto found = frames_->known->find(pointer_); found != frames_->known->end())
      known = found->second;
  }
  Track read;
  if (known == nullptr) {
    read = read_track(check, bounded);
    known = &read;
  }
  out.owned_ = std::make_shared<const nlohmann::json>(
      value_json(track_value(*known, frames_->frame), known->size));
  out.value_ = out.owned_.get();
  if (known == &read && frames_->record != nullptr) {
    if (frames_->record->size() >= frames_->max_tracks) {
      fail_limit("is one track too many: a scene may have " + std::to_string(frames_->max_tracks) +
                     " tracks (limit max_tracks)",
                 "max_tracks", frames_->max_tracks);
    }
    frames_->record->push_back(std::move(read));
  }
  return out;
}

}  // namespace tessera
