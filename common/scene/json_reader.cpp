// JSON text → nlohmann::json, with syntax errors turned into SceneErrors that point at a
// line and column of the text the user wrote.
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "common/scene/json_fast_parse.hpp"
#include "common/scene/scene_parser.hpp"
#include "common/scene/scene_parser_parts.hpp"

namespace tessera {
namespace {

// Smaller arrays cost little as nodes, and stay in the document for any other reader.
constexpr std::size_t lifted_array_min_size = 64;

// 1-based line and column of the byte at `offset`; columns count characters, so UTF-8
// continuation bytes do not advance them.
std::string describe_position(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line;
      column = 1;
    } else if ((c & 0xC0) != 0x80) {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

}  // namespace

// A pre-scan rather than a parser callback, so that nothing is built for a document that
// will be refused anyway.
void check_nesting(std::string_view text) {
  int depth = 0;
  bool in_string = false;
  bool escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_json_nesting) {
        throw SceneError("", "JSON nesting is deeper than " + std::to_string(max_json_nesting) +
                                 " levels at " + describe_position(text, i));
      }
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
}

namespace {

// nlohmann's message carries its own prefix and position ("[json.exception.parse_error.101]
// parse error at line 1, column 7: syntax error ..."); keep only the explanation.
std::string explanation(std::string_view what) {
  if (const auto start = what.find("parse error"); start != std::string_view::npos) {
    if (const auto colon = what.find(": ", start); colon != std::string_view::npos)
      return std::string(what.substr(colon + 2));
  }
  if (const auto bracket = what.find("] ");
      what.starts_with("[json.exception.") && bracket != std::string_view::npos)
    return std::string(what.substr(bracket + 2));
  return std::string(what);
}

// Builds nothing; only notes where and why parsing failed. The DOM parser throws some
// errors (a number overflowing a double) without a position, but every error passes
// through a SAX handler together with one.
class ErrorLocator : public nlohmann::json_sax<nlohmann::json> {
 public:
  std::size_t byte = 0;
  std::string what;

  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string&,
                   const nlohmann::json::exception& error) override {
    byte = position;
    what = error.what();
    return false;
  }
};

}  // namespace

SceneError json_syntax_error(std::string_view text, std::size_t position, std::string_view what) {
  // `position` is the 1-based index of the last character read: the offending one.
  const std::size_t offset = position > 0 ? position - 1 : 0;
  return SceneError(
      "", "invalid JSON at " + describe_position(text, offset) + ": " + explanation(what));
}

nlohmann::json parse_json_text(std::string_view text) {
  // simdjson refuses any text nested deeper than the limit itself, so only a text it
  // refuses needs the pre-scan, a pass over every byte of what may be tens of megabytes.
  if (auto parsed = parse_json_fast(text, max_json_nesting)) return std::move(*parsed);
  check_nesting(text);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& error) {
    ErrorLocator locator;
    nlohmann::json::sax_parse(text, &locator);
    if (locator.what.empty()) locator.what = error.what();
    throw json_syntax_error(text, locator.byte, locator.what);
  }
}

Scene parse_scene_text(std::string_view text, const Limits& limits,
                       const std::function<void(nlohmann::json&)>& edit, const SceneFiles* files,
                       std::optional<int> frame) {
  if (auto fast = parse_json_fast_lifted(text, max_json_nesting, lifted_array_min_size)) {
    if (edit) edit(fast->document);
    try {
      if (frame) return parse_scene_frame(fast->document, *frame, limits, &fast->lifted, files);
      return parse_scene(fast->document, limits, &fast->lifted, files);
    } catch (const LiftedArrayRefused&) {
      // Parsed again below, the ordinary way, for the error's words.
    }
  }
  nlohmann::json document = parse_json_text(text);
  if (edit) edit(document);
  if (frame) return parse_scene_frame(document, *frame, limits, nullptr, files);
  return parse_scene(document, limits, nullptr, files);
}

std::string read_text_file(const std::filesystem::path& path) {
  std::error_code ignored;
  if (std::filesystem::is_directory(path, ignored))
    throw std::runtime_error("cannot read " + path.string() + ": is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path.string() + ": " + std::strerror(errno));
  // In one read of the file's size rather than through a stream buffer: a mesh scene
  // can be tens of megabytes, and every copy of it costs page faults.
  std::string text;
  std::error_code size_error;
  if (const auto size = std::filesystem::file_size(path, size_error); !size_error) {
    text.resize(size);
    in.read(text.data(), static_cast<std::streamsize>(size));
    text.resize(static_cast<std::size_t>(in.gcount()));
  }
  if (in.good()) {  // no size (a pipe), or a file that grew: read on to its end
    std::ostringstream rest;
    rest << in.rdbuf();
    text += rest.str();
  }
  if (in.bad()) throw std::runtime_error("cannot read " + path.string());
  return text;
}

nlohmann::json read_json_file(const std::filesystem::path& path) {
  return parse_json_text(read_text_file(path));
}

}  // namespace tessera
