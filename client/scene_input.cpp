#include "client/scene_input.hpp"

#include <algorithm>
#include <cctype>

#include "common/scene/scene_parser.hpp"
#include "common/scn/scn_import.hpp"
#include "common/text/ascii_case.hpp"

namespace tessera {

std::string read_scene_text(const std::filesystem::path& path, std::optional<int> width,
                            std::optional<int> height) {
  if (ascii_lower(path.extension().string()) != ".scn") return read_text_file(path);
  ScnImportOptions options;
  if (width) options.width = *width;
  if (height) options.height = *height;
  return import_scn(path, options).dump();
}

}  // namespace tessera
