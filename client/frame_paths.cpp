#include "client/frame_paths.hpp"

namespace tessera {

bool has_frame_number(std::string_view pattern) {
  return pattern.find('#') != std::string_view::npos;
}

std::string frame_path(std::string_view pattern, int frame) {
  const std::string number = std::to_string(frame);
  std::string path;
  std::size_t i = 0;
  while (i < pattern.size()) {
    if (pattern[i] != '#') {
      path += pattern[i++];
      continue;
    }
    std::size_t run = 0;
    while (i < pattern.size() && pattern[i] == '#') ++run, ++i;
    if (number.size() < run) path.append(run - number.size(), '0');
    path += number;
  }
  return path;
}

}  // namespace tessera
