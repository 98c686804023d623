#include "common/scn/scn_lexer.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <system_error>

#include "common/text/printable.hpp"

namespace tessera::scn {
namespace {

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

}  // namespace

void Lexer::skip_blanks() {
  while (position_ < text_.size()) {
    const char c = text_[position_];
    if (c == '#') {
      while (position_ < text_.size() && text_[position_] != '\n') ++position_;
    } else if (is_blank(c)) {
      if (c == '\n') ++line_;
      ++position_;
    } else {
      return;
    }
  }
}

std::optional<Token> Lexer::peek() {
  skip_blanks();
  if (position_ == text_.size()) return std::nullopt;
  std::size_t end = position_;
  while (end < text_.size() && !is_blank(text_[end]) && text_[end] != '#') ++end;
  return Token{text_.substr(position_, end - position_), line_};
}

std::optional<Token> Lexer::next() {
  auto token = peek();
  if (token) position_ += token->text.size();
  return token;
}

std::optional<double> parse_number(std::string_view word) {
  // from_chars takes no '+', which strtod, and so the course's fscanf, did.
  if (word.size() > 1 && word[0] == '+' && word[1] != '-') word.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
  if (error != std::errc() || end != word.data() + word.size() || !std::isfinite(value))
    return std::nullopt;
  return value;
}

std::string quote_word(std::string_view word) {
  constexpr std::size_t max_shown = 40;
  if (word.size() <= max_shown) return "'" + printable(word) + "'";
  return "'" + printable(word.substr(0, max_shown)) + "...'";
}

FileText read_bounded(const std::filesystem::path& file, std::uintmax_t max_bytes) {
  std::error_code ignored;
  if (std::filesystem::is_directory(file, ignored)) return {std::nullopt, "is a directory"};
  std::ifstream in(file, std::ios::binary);
  if (!in) return {std::nullopt, std::strerror(errno)};
  std::string text;
  char buffer[1 << 16];
  // Read in pieces rather than by the file's size, so that a pipe or a device such as
  // /dev/zero stops at the limit too.
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes) {
      return {std::nullopt, "is larger than " + std::to_string(max_bytes) + " bytes"};
    }
  }
  if (in.bad()) return {std::nullopt, "read error"};
  return {std::move(text), ""};
}

}  // namespace tessera::scn
