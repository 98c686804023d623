#include "common/scene/json_fast_parse.hpp"

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

// `root` lives in `parser`'s memory. False wherever simdjson refuses the text.
bool parse_dom(simdjson::dom::parser& parser, std::string_view text, std::size_t max_depth,
               simdjson::dom::element& root) {
  if (parser.allocate(text.size(), max_depth) != simdjson::SUCCESS) return false;
  // `true`: simdjson copies the text when reading past its end could cross a page.
  return parser.parse(text.data(), text.size(), true).get(root) == simdjson::SUCCESS;
}

// Each element an array of exactly three numbers (`indices`: non-negative integers).
bool lift(simdjson::dom::array array, bool indices, LiftedTriples& out) {
  if (indices)
    out.indices.reserve(3 * array.size());
  else
    out.numbers.reserve(3 * array.size());
  for (const simdjson::dom::element element : array) {
    if (element.type() != element_type::ARRAY) return false;
    const simdjson::dom::array triple = element.get_array().value_unsafe();
    std::size_t count = 0;
    for (const simdjson::dom::element number : triple) {
      if (++count > 3) return false;
      const element_type type = number.type();
      if (indices) {
        if (type == element_type::UINT64) {
          out.indices.push_back(number.get_uint64().value_unsafe());
        } else if (type == element_type::INT64 && number.get_int64().value_unsafe() >= 0) {
          out.indices.push_back(static_cast<std::uint64_t>(number.get_int64().value_unsafe()));
        } else {
          return false;
        }
      } else if (type == element_type::DOUBLE) {
        out.numbers.push_back(number.get_double().value_unsafe());
      } else if (type == element_type::INT64) {
        // As to_json() stores it (unsigned when non-negative) and get<double>() reads it.
        const std::int64_t value = number.get_int64().value_unsafe();
        out.numbers.push_back(value >= 0 ? static_cast<double>(static_cast<std::uint64_t>(value))
                                         : static_cast<double>(value));
      } else if (type == element_type::UINT64) {
        out.numbers.push_back(static_cast<double>(number.get_uint64().value_unsafe()));
      } else {
        return false;
      }
    }
    if (count != 3) return false;
  }
  return true;
}

// An object of the root's "objects": converted as to_json() would, but a mesh's big arrays
// lifted out into `lifted`, under `pointer` + "/" + their key.
json object_lifting_arrays(simdjson::dom::object object, const std::string& pointer,
                           std::size_t min_size, LiftedArrays& lifted) {
  // The last "type" wins, as the last of repeated keys does in the document.
  bool mesh = false;
  for (const simdjson::dom::key_value_pair member : object)
    if (member.key == "type")
      mesh = member.value.type() == element_type::STRING &&
             member.value.get_string().value_unsafe() == "mesh";
  json::object_t members;
  for (const simdjson::dom::key_value_pair member : object) {
    const std::string key(member.key);
    const std::string where = pointer + "/" + key;
    const bool liftable = mesh && member.value.type() == element_type::ARRAY &&
                          (key == "positions" || key == "normals" || key == "triangles") &&
                          member.value.get_array().value_unsafe().size() >= min_size;
    LiftedTriples triples;
    if (liftable && lift(member.value.get_array().value_unsafe(), key == "triangles", triples)) {
      lifted.insert_or_assign(where, std::move(triples));
      members.insert_or_assign(key, json::array());
    } else {
      lifted.erase(where);  // an earlier member of the same key, lifted, lost to this one
      members.insert_or_assign(key, to_json(member.value));
    }
  }
  return json(std::move(members));
}

}  // namespace

std::optional<LiftedDocument> parse_json_fast_lifted(std::string_view text, std::size_t max_depth,
                                                     std::size_t min_size) {
  simdjson::dom::parser parser;
  simdjson::dom::element root;
  if (!parse_dom(parser, text, max_depth, root)) return std::nullopt;
  LiftedDocument result;
  if (root.type() != element_type::OBJECT) {
    result.document = to_json(root);
    return result;
  }
  json::object_t members;
  const simdjson::dom::object root_object = root.get_object().value_unsafe();
  for (const simdjson::dom::key_value_pair member : root_object) {
    const std::string key(member.key);
    // Of repeated "objects", only the last one's arrays stay lifted.
    if (key == "objects") result.lifted.clear();
    if (key != "objects" || member.value.type() != element_type::ARRAY) {
      members.insert_or_assign(key, to_json(member.value));
      continue;
    }
    const simdjson::dom::array objects = member.value.get_array().value_unsafe();
    json::array_t elements;
    elements.reserve(objects.size());
    std::size_t index = 0;
    for (const simdjson::dom::element element : objects) {
      const std::string pointer = "/objects/" + std::to_string(index++);
      elements.push_back(element.type() == element_type::OBJECT
                             ? object_lifting_arrays(element.get_object().value_unsafe(), pointer,
                                                     min_size, result.lifted)
                             : to_json(element));
    }
    members.insert_or_assign(key, json(std::move(elements)));
  }
  result.document = json(std::move(members));
  return result;
}

std::optional<json> parse_json_fast(std::string_view text, std::size_t max_depth) {
  simdjson::dom::parser parser;
  simdjson::dom::element root;
  if (!parse_dom(parser, text, max_depth, root)) return std::nullopt;
  return to_json(root);
}

}  // namespace tessera
