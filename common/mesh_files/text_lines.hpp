// The lines of a text file with their numbers, for the formats whose errors name a line.
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

namespace tessera {

class TextLines {
 public:
  explicit TextLines(std::string_view text) : text_(text) {}

  // The next line (without its "\r\n" or "\n") and its 1-based number; false at the end.
  bool next(std::string_view& line) {
    if (position_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', position_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    line = text_.substr(position_, stop - position_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    position_ = stop + 1;
    ++number_;
    return true;
  }
  std::size_t number() const { return number_; }
  std::size_t offset() const { return position_ > text_.size() ? text_.size() : position_; }
  std::size_t remaining_bytes() const { return text_.size() - offset(); }

 private:
  std::string_view text_;
  std::size_t position_ = 0;
  std::size_t number_ = 0;
};

// The whitespace-separated words of `line`, up to a '#' comment when `comments`.
inline void split_words(std::string_view line, std::vector<std::string_view>& words,
                        bool comments = true) {
  words.clear();
  if (comments) line = line.substr(0, line.find('#'));
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
}

}  // namespace tessera
