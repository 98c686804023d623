// libFuzzer target: any bytes as a scene document. The parser and validator must answer
// every input with a Scene or a SceneError (with a JSON Pointer); anything else, a crash,
// a sanitizer report, a hang or another exception, is a bug. And whatever the fast JSON
// parser accepts, nlohmann must accept too and read as the same document.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include <nlohmann/json.hpp>

#include "common/scene/json_fast_parse.hpp"
#include "common/scene/scene_error.hpp"
#include "common/scene/scene_parser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (const auto fast = tessera::parse_json_fast(text, 64)) {
    const nlohmann::json slow = nlohmann::json::parse(text, nullptr, false);
    if (slow.is_discarded() || slow != *fast || slow.dump() != fast->dump()) __builtin_trap();
  }
  // Small limits, so that a valid input cannot ask for gigabytes of mesh.
  tessera::Limits limits;
  limits.max_objects = 64;
  limits.max_triangles = 4096;
  limits.max_materials = 64;
  limits.max_lights = 16;
  try {
    const tessera::Scene scene = tessera::parse_scene_text(text, limits);
    (void)scene;
  } catch (const tessera::SceneError& error) {
    // The pointer of every error is a JSON Pointer: empty or starting with '/'.
    if (!error.pointer().empty() && error.pointer().front() != '/') __builtin_trap();
  }
  return 0;
}
