// Text that came from outside (a name, a server's message, a path), made safe to print
// on a terminal or to write as one log line: it can neither end the line nor send escape
// sequences.
#pragma once

#include <string>
#include <string_view>

namespace tessera {

// `text` with every control character (C0, DEL and, in UTF-8, C1 and the bidirectional
// formatting characters, U+202E and its kin) and every byte that is not part of valid UTF-8
// written as \xNN; everything else, other scripts included, as it is.
std::string printable(std::string_view text);

// The offset of the first control character (as above) in `text`, or npos.
std::size_t find_control_character(std::string_view text);
// The character at `at` (all of its bytes), as printable() writes it.
std::string control_sequence_at(std::string_view text, std::size_t at);

}  // namespace tessera
