// Keyframed scenes: a scene's "animation" gives its range of frames, and any animatable
// number or vector of the scene may be a track of keys instead of a value
// (docs/scene-format.md, "Animation"). Frame n of a scene is the static scene that holds
// each track's value at n, read by the same rules.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tessera {

// Frame numbers are 0 to this: seven digits, and never negative, since "1-5" is a range.
inline constexpr int max_frame_number = 9'999'999;

enum class Interpolation : std::uint8_t { linear, smooth, step };
inline constexpr std::string_view interpolation_names[] = {"linear", "smooth", "step"};

// One key of a track: a number, or a vector or colour of three; `size` says which.
struct TrackKey {
  int frame = 0;
  std::array<double, 3> value{};
};

// What a track animates, which says what a renderer must build again when it moves.
enum class TrackTarget : std::uint8_t {
  camera,
  light,
  background,      // "background" and "ambient_light"
  named_material,  // a material under "materials"
  object,          // an object's transform or its inline material
};

struct Track {
  std::string pointer;  // the animated field's JSON Pointer, such as "/camera/eye"
  TrackTarget target = TrackTarget::camera;
  Interpolation interpolation = Interpolation::linear;
  // 1 or 3: a track whose keys are all numbers gives numbers, any other gives triples
  // (a number key of a colour or a scale standing for three equal ones).
  int size = 1;
  // Smooth values stay between the two keys around them, component by component, for a
  // field with bounds (a colour, a cone's cutoff): see docs/scene-format.md.
  bool bounded = false;
  std::vector<TrackKey> keys;  // at least one, frames strictly increasing
};

// The value of `track` at `frame` (docs/scene-format.md gives the formulas).
std::array<double, 3> track_value(const Track& track, int frame);

// A scene's "animation", or a still scene's single frame 0.
struct Animation {
  bool animated = false;  // the scene has "animation"
  int first = 0;
  int last = 0;
  double fps = 24.0;
  std::vector<Track> tracks;

  std::int64_t frame_count() const { return std::int64_t{last} - first + 1; }
  bool contains(int frame) const { return frame >= first && frame <= last; }
  // Whether the objects must be read again for another frame: a track in an object's
  // transform or inline material, or in a named material's transmission.
  bool changes_objects() const;
  bool changes(TrackTarget target) const;
};

}  // namespace tessera
