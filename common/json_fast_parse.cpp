#include "common/json_fast_parse.hpp"

#include <string>
#include <utility>

#include <simdjson.h>

namespace tessera {
namespace {

using nlohmann::json;
using simdjson::dom::element_type;

// Recursion is bounded: simdjson refuses documents nested deeper than its max_depth.
json to_json(simdjson::dom::element value) {
  switch (value.type()) {
    case element_type::ARRAY: {
      const simdjson::dom::array array = value.get_array().value_unsafe();
      json::array_t elements;
      elements.reserve(array.size());
      for (const simdjson::dom::element element : array) elements.push_back(to_json(element));
      return json(std::move(elements));
    }
    case element_type::OBJECT: {
      const simdjson::dom::object object = value.get_object().value_unsafe();
      json::object_t members;
      // The last of repeated keys wins, as in nlohmann's parser.
      for (const simdjson::dom::key_value_pair member : object)
        members.insert_or_assign(std::string(member.key), to_json(member.value));
      return json(std::move(members));
    }
    case element_type::INT64: {
      // nlohmann keeps non-negative integers unsigned.
      const std::int64_t number = value.get_int64().value_unsafe();
      if (number >= 0) return json(static_cast<std::uint64_t>(number));
      return json(number);
    }
    case element_type::UINT64:
      return json(value.get_uint64().value_unsafe());
    case element_type::DOUBLE:
      return json(value.get_double().value_unsafe());
    case element_type::STRING:
      return json(std::string(value.get_string().value_unsafe()));
    case element_type::BOOL:
      return json(value.get_bool().value_unsafe());
    case element_type::NULL_VALUE:
      break;
  }
  return json(nullptr);
}

}  // namespace

std::optional<json> parse_json_fast(std::string_view text, std::size_t max_depth) {
  simdjson::dom::parser parser;
  if (parser.allocate(text.size(), max_depth) != simdjson::SUCCESS) return std::nullopt;
  simdjson::dom::element root;
  // `true`: simdjson copies the text when reading past its end could cross a page.
  if (parser.parse(text.data(), text.size(), true).get(root) != simdjson::SUCCESS)
    return std::nullopt;
  return to_json(root);
}

}  // namespace tessera
