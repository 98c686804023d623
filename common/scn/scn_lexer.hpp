// Internal to the .scn importer (scn_import.cpp): the words of a COS 426 scene file, each
// with the line it is on, and the numbers among them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace tessera::scn {

struct Token {
  std::string_view text;
  std::size_t line = 0;  // 1-based
};

// Splits text at whitespace. '#' starts a comment that runs to the end of its line,
// wherever it appears: the course's reader only knew comments at the start of a command,
// but a '#' anywhere else made its number reads fail, so no valid file has one there.
class Lexer {
 public:
  explicit Lexer(std::string_view text) : text_(text) {}

  std::optional<Token> peek();
  std::optional<Token> next();

 private:
  void skip_blanks();

  std::string_view text_;
  std::size_t position_ = 0;
  std::size_t line_ = 1;
};

// The number a whole word spells, as the C library's strtod would read it (a leading '+'
// included), or nothing: also for infinities and NaNs, which no scene can use.
std::optional<double> parse_number(std::string_view word);

// A word quoted for a message, cut short when long and escaped where not printable.
std::string quote_word(std::string_view word);

// The bytes of a file, at most `max_bytes` of them; `error` says why there are none.
struct FileText {
  std::optional<std::string> text;
  std::string error;
};
FileText read_bounded(const std::filesystem::path& file, std::uintmax_t max_bytes);

}  // namespace tessera::scn
