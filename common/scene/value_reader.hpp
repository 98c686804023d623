// Internal to the scene parser: typed access to one JSON value that knows its own JSON
// Pointer, so that every rule reports exactly where it was broken.
#pragma once

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "common/scene/animation.hpp"
#include "common/scene/json_fast_parse.hpp"
#include "common/scene/scene.hpp"
#include "common/scene/scene_error.hpp"

namespace tessera {

// The interval a number must lie in; an absent end is unbounded.
struct Range {
  std::optional<double> min;
  std::optional<double> max;
  bool min_open = false;
  bool max_open = false;

  static Range at_least(double min) { return {min, std::nullopt, false, false}; }
  static Range above(double min) { return {min, std::nullopt, true, false}; }
  static Range between(double min, bool min_open, double max, bool max_open) {
    return {min, max, min_open, max_open};
  }

  bool contains(double value) const;
  std::string describe() const;  // ">= 0", "in (0, 180)"
};

// Inclusive bounds for integers; `max_reason` names where the maximum comes from.
struct IntRange {
  std::int64_t min = std::numeric_limits<std::int64_t>::min();
  std::int64_t max = std::numeric_limits<std::int64_t>::max();
  // Where the maximum comes from, e.g. "the mesh has 4 positions"; "limit NAME" for the
  // Limits member NAME, which makes exceeding it a limit error (SceneError::limit()).
  std::string max_reason;
};

// RFC 6901: "~" becomes "~0" and "/" becomes "~1", since keys are user-chosen names.
std::string pointer_token(std::string_view key);
std::string quote(std::string_view text);
std::string quoted_list(std::span<const std::string_view> words);  // "a", "b", "c"
std::string format_number(double value);
// A short rendering of a value for the "got ..." part of a message.
std::string describe(const nlohmann::json& value);
// Unit vector, or nothing for the zero vector; pre-scaling keeps tiny vectors from
// underflowing to a zero length.
std::optional<Vec3> try_normalize(const Vec3& v);
// The common case of ValueReader::vec3(), without building a JSON Pointer for each
// element: a mesh has millions. Nothing when `value` is anything but [x, y, z] of finite
// numbers; ValueReader::vec3() then says what is wrong, and where.
std::optional<Vec3> plain_vec3(const nlohmann::json& value);

// How a reading of the scene treats keyframe tracks (common/scene/animation.hpp): the frame whose
// values it reads, and whether it checks and records each track it meets.
struct FrameReading {
  const Animation* animation = nullptr;  // the scene's; a track is refused when not animated
  int frame = 0;
  // Where the first reading records each track, after checking its keys by the field's own
  // rule; null when reading again at another frame.
  std::vector<Track>* record = nullptr;
  std::size_t max_tracks = 0;
  // The tracks a reading at another frame takes its values from, by pointer, instead of
  // reading their keys again.
  const std::map<std::string, const Track*, std::less<>>* known = nullptr;
  // Whether a value holding a track is read again at every other frame (read_every_frame()).
  bool every_frame = false;
};

class ValueReader {
 public:
  // `lifted`: the arrays lifted out of the document (parse_json_fast_lifted()), if any.
  // `frames`: how tracks are read; with none, a track is refused.
  ValueReader(const nlohmann::json& value, std::string pointer,
              const LiftedArrays* lifted = nullptr, const FrameReading* frames = nullptr)
      : value_(&value), pointer_(std::move(pointer)), lifted_(lifted), frames_(frames) {}

  const nlohmann::json& json() const { return *value_; }
  const std::string& pointer() const { return pointer_; }
  // The lifted array this value stands for, or null.
  const LiftedTriples* lifted() const;

  [[noreturn]] void fail(const std::string& detail) const { throw SceneError(pointer_, detail); }
  // Over `limit` (a Limits member's name), whose value is `value`.
  [[noreturn]] void fail_limit(const std::string& detail, const std::string& limit,
                               std::uint64_t value) const {
    throw SceneError(pointer_, detail, limit, value);
  }
  // "must be <expected>, got <JSON type>"
  [[noreturn]] void fail_type(std::string_view expected) const;

  ValueReader element(std::size_t index) const;
  ValueReader member(std::string_view key) const;

  // The array's size; `expected` describes what the array should hold.
  std::size_t array_size(std::string_view expected = "an array") const;
  // As array_size, but the array must have exactly `size` elements.
  void expect_array_of(std::size_t size, std::string_view expected) const;

  double number(const Range& range = {}) const;
  // Integral JSON numbers only; 5.0 counts as 5, 5.5 does not.
  std::int64_t integer(const IntRange& range = {}) const;
  bool boolean() const;
  const std::string& string() const;
  std::string_view choice(std::span<const std::string_view> allowed) const;
  Vec3 vec3() const;
  Vec3 direction() const;  // non-zero; returned normalized
  Color color() const;     // [r, g, b] or one number for gray; finite and >= 0

  const FrameReading* frames() const { return frames_; }
  // This value read at another frame (`frames` outliving the copy).
  ValueReader at(const FrameReading& frames) const;
  // A keyframe track, {"keys": [...], "interpolation": ...}, where a value belongs.
  bool is_track() const { return value_->is_object() && value_->contains("keys"); }
  // An animatable value: `read` (the field's own rule, such as
  // [](const ValueReader& v) { return v.vec3(); }) applied to the value, or, for a track,
  // to its value at the reading's frame, once `read` has accepted each of its keys.
  // `bounded`: the field has bounds, which a smooth track's values must keep (Track).
  template <typename Read>
  auto animated(Read read, bool bounded = false) const -> decltype(read(*this)) {
    if (!is_track()) return read(*this);
    return read(track_at_frame([&](const ValueReader& key) { (void)read(key); }, bounded));
  }

 private:
  ValueReader track_at_frame(const std::function<void(const ValueReader&)>& check,
                             bool bounded) const;
  Track read_track(const std::function<void(const ValueReader&)>& check, bool bounded) const;

  const nlohmann::json* value_;
  std::string pointer_;
  const LiftedArrays* lifted_;
  const FrameReading* frames_;
  // The value of a track at a frame, which no document holds.
  std::shared_ptr<const nlohmann::json> owned_;
};

// A JSON object whose keys are checked against the ones its part of the format knows.
class ObjectReader {
 public:
  // `expected` describes the object in the error for a non-object value.
  explicit ObjectReader(ValueReader value, std::string_view expected = "an object");

  // Runs before reading any member, so that a misspelt key is reported as such rather
  // than as the required key it was meant to be.
  void allow_only(std::span<const std::string_view> keys) const;
  void allow_only(std::initializer_list<std::string_view> keys) const {
    allow_only(std::span<const std::string_view>(keys.begin(), keys.size()));
  }

  const ValueReader& value() const { return value_; }
  const std::string& pointer() const { return value_.pointer(); }
  const nlohmann::json::object_t& members() const;

  std::optional<ValueReader> find(std::string_view key) const;
  ValueReader require(std::string_view key) const;  // "required" error at the missing key

  double number_or(std::string_view key, double fallback, const Range& range = {}) const;
  std::int64_t integer_or(std::string_view key, std::int64_t fallback,
                          const IntRange& range = {}) const;
  bool boolean_or(std::string_view key, bool fallback) const;
  Color color_or(std::string_view key, const Color& fallback) const;
  Vec3 vec3_or(std::string_view key, const Vec3& fallback) const;
  // The same for animatable fields: the value may be a track (ValueReader::animated()).
  double animated_number_or(std::string_view key, double fallback, const Range& range) const;
  Color animated_color_or(std::string_view key, const Color& fallback) const;
  Vec3 animated_vec3_or(std::string_view key, const Vec3& fallback) const;

 private:
  ValueReader value_;
};

}  // namespace tessera
