// Names people may type in any case (URL schemes, header names, file extensions), made
// lower case for comparing. ASCII letters only, whatever the locale: "Ä" stays "Ä".
#pragma once

#include <string>
#include <string_view>

namespace tessera {

inline std::string ascii_lower(std::string_view text) {
  std::string out(text);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

}  // namespace tessera
