// A fast first try at parsing JSON text, for the scene documents of big meshes: simdjson
// reads 52 MB of mesh in a fraction of the time nlohmann's own parser takes.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <nlohmann/json.hpp>

namespace tessera {

// The document nlohmann::json::parse(text) would give, or nothing wherever simdjson
// refuses the text. That covers every syntax error and every text nested deeper than
// `max_depth` arrays and objects, but also some texts nlohmann accepts: integers beyond 64
// bits, a byte order mark. The caller then parses with nlohmann, which accepts those and
// words the errors. One difference remains: "-0" comes back as an unsigned rather than a
// signed integer 0, the same number.
std::optional<nlohmann::json> parse_json_fast(std::string_view text, std::size_t max_depth);

// A big array of a mesh lifted out of the document as flat numbers: 3 per element, in
// order. `numbers` for positions and normals (each number as nlohmann's get<double>() gives
// it), `indices` for triangles (non-negative JSON integers).
struct LiftedTriples {
  std::vector<double> numbers;
  std::vector<std::uint64_t> indices;
};
// By the JSON Pointer of the array, such as "/objects/3/positions".
using LiftedArrays = std::unordered_map<std::string, LiftedTriples>;

struct LiftedDocument {
  nlohmann::json document;  // an empty array where each lifted array was
  LiftedArrays lifted;
};

// As parse_json_fast(), but the "positions", "normals" and "triangles" of each object of
// type "mesh" in the root's "objects" that have at least `min_size` elements, all of them
// arrays of three JSON numbers (non-negative integers for triangles), come out as
// LiftedTriples instead of nlohmann nodes: a million-triangle mesh is millions of nodes,
// which take longer to build and free than to parse.
std::optional<LiftedDocument> parse_json_fast_lifted(std::string_view text, std::size_t max_depth,
                                                     std::size_t min_size);

// Thrown by the scene parser where a lifted array breaks a rule: it has no JSON to point
// into, so the caller parses the whole document again the ordinary way, which words the
// error.
struct LiftedArrayRefused {};

}  // namespace tessera
