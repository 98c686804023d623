// Helpers shared by the scene parser tests: a minimal valid scene to break one rule at a
// time, and an assertion on where and why parsing failed.
#pragma once

#include <initializer_list>
#include <string>
#include <string_view>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/scene/scene_parser.hpp"

namespace tessera::scene_test {

using nlohmann::json;

inline json minimal_scene() {
  return json::parse(R"({
    "image": {"width": 4, "height": 3},
    "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]}
  })");
}

// `document` with the value at `pointer` replaced (or added).
inline json with(json document, const std::string& pointer, json value) {
  document[json::json_pointer(pointer)] = std::move(value);
  return document;
}

inline json with_object(json object) {
  return with(minimal_scene(), "/objects", json::array({std::move(object)}));
}

inline json with_light(json light) {
  return with(minimal_scene(), "/lights", json::array({std::move(light)}));
}

inline json sphere() { return {{"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}}; }

// Passes when parsing throws a SceneError at exactly `pointer` whose detail contains every
// fragment.
inline ::testing::AssertionResult fails_at(const json& document, std::string_view pointer,
                                           std::initializer_list<std::string_view> fragments,
                                           const Limits& limits = {}) {
  try {
    parse_scene(document, limits);
  } catch (const SceneError& error) {
    if (error.pointer() != pointer) {
      return ::testing::AssertionFailure() << "pointer \"" << error.pointer() << "\" instead of \""
                                           << pointer << "\" (" << error.what() << ")";
    }
    for (std::string_view fragment : fragments) {
      if (error.detail().find(fragment) == std::string::npos) {
        return ::testing::AssertionFailure()
               << "\"" << fragment << "\" missing from: " << error.what();
      }
    }
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "parsed without error; expected one at " << pointer;
}

}  // namespace tessera::scene_test
