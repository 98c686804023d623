// "a, b or c": the choices an error message lists.
#pragma once

#include <span>
#include <string>
#include <string_view>

namespace tessera {

inline std::string or_list(std::span<const std::string_view> words) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i > 0) text += i + 1 == words.size() ? " or " : ", ";
    text += words[i];
  }
  return text;
}

}  // namespace tessera
