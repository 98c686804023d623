// A scene read with its objects apart from the rest: the coordinator checks a scene of a
// hundred thousand objects one object at a time, since nlohmann's nodes take ten times
// the bytes of the JSON text they come from (a std::map node for every key).
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/scene/json_fast_parse.hpp"
#include "common/scene/scene.hpp"
#include "common/scene/scene_files.hpp"

namespace tessera {

// The elements of a scene's "objects" as compact JSON text, each nlohmann's dump() of it,
// joined by commas: the inside of the brackets of that array in the scene's dump().
class ObjectTexts {
 public:
  // `bytes`: the room to set aside, so that growing does not copy (untouched, it costs no
  // memory).
  void reserve(std::size_t bytes) { text_.reserve(bytes); }
  void clear();
  void add_text(std::string_view element);  // an element's dump()
  void add(const nlohmann::json& element) { add_text(element.dump()); }

  std::size_t size() const { return ends_.size(); }
  std::string_view text(std::size_t index) const;
  nlohmann::json element(std::size_t index) const;  // parsed again from text(index)
  // A mesh's element parsed again with its big arrays in `lifted` (json_fast_parse.hpp,
  // keyed under `pointer`, the element's JSON Pointer), or nothing for any other element, or
  // one whose arrays are not all of three numbers: element() then.
  std::optional<nlohmann::json> element_lifted(std::size_t index, const std::string& pointer,
                                               LiftedArrays& lifted) const;

  // The joined texts, leaving this empty.
  std::string take() &&;

 private:
  std::string text_;
  std::vector<std::size_t> ends_;  // where each element's text ends in text_
};

// nlohmann::json::parse(text), but the elements of the scene's "objects" array go into
// `objects` as their dump() is written from what the parser reads, and that array stays
// empty in the document: no object is ever in nodes. A member of the scene that
// parse_scene() refuses by its key alone, or of the root that is not in `envelope_keys`
// (when given), has null for its value, not built. `scene_member` as for
// scan_scene_limits(), which should have passed `text` first (this one refuses too deep a
// text, but builds what comes before it). Throws parse_json_text()'s SceneError for a
// syntax error.
nlohmann::json parse_json_objects_apart(std::string_view text,
                                        std::optional<std::string_view> scene_member,
                                        ObjectTexts& objects,
                                        std::span<const std::string_view> envelope_keys = {});

// parse_scene(), with the same errors, for a scene whose "objects" are `objects` (an empty
// "objects" array in `document` stands for them). The Scene has no objects: each is
// checked and dropped, for a caller that only needs to know the scene is valid.
Scene check_scene(const nlohmann::json& document, const Limits& limits, const ObjectTexts& objects,
                  const SceneFiles* files = nullptr);

// The bytes of document.dump() were its "objects" array filled with `objects`, made by
// moving their text rather than copying it.
std::string dump_scene(const nlohmann::json& document, ObjectTexts&& objects);

}  // namespace tessera
