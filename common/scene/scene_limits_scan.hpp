// A pass over a scene's JSON text that builds nothing: it checks the syntax and the
// nesting, and counts what Limits caps by number (objects, lights, materials, triangles),
// so that a text over a limit is refused having cost no more memory than its own bytes.
#pragma once

#include <optional>
#include <string_view>

#include "common/scene/scene.hpp"
#include "common/scene/scene_error.hpp"

namespace tessera {

// Throws a SceneError at the first thing, in the order of the text, that parse_scene
// (with parse_json_text) would refuse as one of these:
//  - a syntax error or nesting deeper than 64 levels: parse_json_text()'s error, at "";
//  - over max_objects or max_lights: the limit's error at "/objects" or "/lights", as soon
//    as the first element too many begins (the rest of the text is not read);
//  - over max_materials: at "/materials" for the named ones, at the inline material that
//    goes over ("/objects/7/material") for the others;
//  - over max_triangles: at "/objects", counting up to the object that goes over;
//  - a piece (a member of the scene or of "materials", an element of "objects" or
//    "lights") of more than 65,536 JSON values outside a mesh's positions, normals and
//    triangles, at its pointer: no valid piece comes close, and each is built as nodes
//    whole when it is checked. parse_scene itself has no such rule.
// Otherwise returns: the text is valid JSON within those limits, and parse_scene still
// checks everything else. `scene_member`: the root member that holds the scene (a job
// submission's "scene"), or nothing when the root is the scene; pointers are the scene's.
// A member the text repeats is counted afresh, as the last one is the one that counts.
void scan_scene_limits(std::string_view text, const Limits& limits,
                       std::optional<std::string_view> scene_member = std::nullopt);

}  // namespace tessera
