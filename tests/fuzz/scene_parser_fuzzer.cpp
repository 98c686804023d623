// libFuzzer target: any bytes as a scene document. The parser and validator must answer
// every input with a Scene or a SceneError (with a JSON Pointer); anything else, a crash,
// a sanitizer report, a hang or another exception, is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "common/scene_error.hpp"
#include "common/scene_parser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
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
