// Every answer the farm tests receive, checked against docs/openapi.yaml: its status must be
// one the contract declares for the route, and its JSON body must fit the schema declared
// for that status (types, required and unknown properties, nullable, enums, bounds). A
// violation fails the test that received the answer. Read with yaml-cpp; without it (see
// tests/CMakeLists.txt) the check is off and says so once.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/net/http_client.hpp"

#if TESSERA_CONTRACT_CHECK
#include <yaml-cpp/yaml.h>
#endif

namespace tessera::test {

#if TESSERA_CONTRACT_CHECK

class Contract {
 public:
  // The YAML is turned into JSON once: yaml-cpp's nodes are not safe to read from the many
  // threads of a load test, nlohmann's const ones are.
  explicit Contract(const std::filesystem::path& file)
      : root_(to_json(YAML::LoadFile(file.string()))) {}

  // The problems of one answer; none when it keeps to the contract.
  std::vector<std::string> problems(std::string_view method, std::string_view target,
                                    const HttpResult& result) const {
    std::vector<std::string> found;
    const std::string where = std::string(method) + " " + std::string(target) + " answered " +
                              std::to_string(result.status);
    if (method == "HEAD") return found;  // the GET's header, without the body
    const std::string path(target.substr(0, target.find('?')));
    const nlohmann::json* item = path_item(path);
    const nlohmann::json body = nlohmann::json::parse(result.body, nullptr, false);
    // A route the contract does not have (404), or a method its path does not (405): the
    // one error shape.
    const nlohmann::json* operation = item ? find(*item, lower(method)) : nullptr;
    if (!operation) {
      if (result.status != 404 && result.status != 405)
        found.push_back(where + ", for a route docs/openapi.yaml does not have");
      check(resolve(root_["components"]["schemas"]["Error"]), body, "", where, found);
      return found;
    }
    const nlohmann::json* declared = find((*operation)["responses"], std::to_string(result.status));
    if (!declared) {
      found.push_back(where + ", which docs/openapi.yaml does not declare for it");
      return found;
    }
    const nlohmann::json& response = resolve(*declared);
    if (!response.contains("content")) {
      if (!result.body.empty()) found.push_back(where + " with a body where none is declared");
      return found;
    }
    const nlohmann::json* json_content = find(response["content"], "application/json");
    if (!json_content) return found;  // an image or a scene's text: not JSON
    if (body.is_discarded()) {
      found.push_back(where + " with a body that is not JSON: " + result.body.substr(0, 200));
      return found;
    }
    check(resolve((*json_content)["schema"]), body, "", where, found);
    return found;
  }

 private:
  // Scalars as YAML 1.2's core schema reads them: booleans, numbers, the rest text.
  static nlohmann::json to_json(const YAML::Node& node) {
    if (node.IsMap()) {
      nlohmann::json object = nlohmann::json::object();
      for (const auto& entry : node) object[entry.first.as<std::string>()] = to_json(entry.second);
      return object;
    }
    if (node.IsSequence()) {
      nlohmann::json array = nlohmann::json::array();
      for (const auto& element : node) array.push_back(to_json(element));
      return array;
    }
    if (!node.IsScalar()) return nullptr;
    const std::string text = node.Scalar();
    if (node.Tag() != "!") {  // not quoted
      if (text == "true" || text == "false") return text == "true";
      char* end = nullptr;
      const double number = std::strtod(text.c_str(), &end);
      if (!text.empty() && end == text.c_str() + text.size()) return number;
    }
    return text;
  }

  static const nlohmann::json* find(const nlohmann::json& object, const std::string& key) {
    if (!object.is_object()) return nullptr;
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }

  static std::string lower(std::string_view text) {
    std::string out(text);
    for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
  }

  // The path item whose template fits `path` ("/v1/jobs/{id}" fits "/v1/jobs/j-1"); a
  // literal segment beats a parameter, as in the server's router.
  const nlohmann::json* path_item(const std::string& path) const {
    const nlohmann::json* best = nullptr;
    int best_literals = -1;
    const std::vector<std::string> parts = split(path);
    for (const auto& [pattern_text, item] : root_["paths"].items()) {
      const std::vector<std::string> pattern = split(pattern_text);
      if (pattern.size() != parts.size()) continue;
      int literals = 0;
      bool fits = true;
      for (std::size_t i = 0; i < parts.size() && fits; ++i) {
        const bool parameter = !pattern[i].empty() && pattern[i].front() == '{';
        fits = parameter ? !parts[i].empty() : pattern[i] == parts[i];
        literals += parameter ? 0 : 1;
      }
      if (fits && literals > best_literals) {
        best = &item;
        best_literals = literals;
      }
    }
    return best;
  }

  static std::vector<std::string> split(const std::string& path) {
    std::vector<std::string> parts;
    std::size_t at = 1;
    while (at <= path.size()) {
      const std::size_t slash = path.find('/', at);
      parts.push_back(path.substr(at, slash == std::string::npos ? std::string::npos : slash - at));
      if (slash == std::string::npos) break;
      at = slash + 1;
    }
    return parts;
  }

  // "#/components/schemas/X" and "#/components/responses/X" followed to what they name.
  const nlohmann::json& resolve(const nlohmann::json& node) const {
    const nlohmann::json* at = &node;
    while (at->is_object() && at->contains("$ref"))
      at = &root_.at(nlohmann::json::json_pointer(at->at("$ref").get<std::string>().substr(1)));
    return *at;
  }

  void check(const nlohmann::json& schema, const nlohmann::json& value, const std::string& pointer,
             const std::string& where, std::vector<std::string>& found) const {
    const auto fail = [&](const std::string& why) {
      found.push_back(where + ": " + (pointer.empty() ? "the body" : pointer) + " " + why);
    };
    if (!schema.is_object()) return;
    if (value.is_null()) {
      if (!schema.value("nullable", false)) fail("is null");
      return;
    }
    const std::string type = schema.value("type", "");
    if (type == "object") {
      if (!value.is_object()) return fail("is not an object");
      for (const auto& name : schema.value("required", nlohmann::json::array()))
        if (!value.contains(name.get<std::string>()))
          fail("lacks the required " + name.get<std::string>());
      const nlohmann::json* properties = find(schema, "properties");
      for (const auto& [name, member] : value.items()) {
        const nlohmann::json* property = properties ? find(*properties, name) : nullptr;
        if (!property) {
          if (properties) fail("has " + name + ", which the schema does not list");
          continue;
        }
        check(resolve(*property), member, pointer + "/" + name, where, found);
      }
    } else if (type == "array") {
      if (!value.is_array()) return fail("is not an array");
      const nlohmann::json* items = find(schema, "items");
      for (std::size_t i = 0; i < value.size() && items; ++i)
        check(resolve(*items), value[i], pointer + "/" + std::to_string(i), where, found);
    } else if (type == "string") {
      if (!value.is_string()) return fail("is not a string");
      if (schema.contains("maxLength") &&
          static_cast<double>(value.get<std::string>().size()) > schema["maxLength"].get<double>())
        fail("is longer than its maxLength");
    } else if (type == "integer" || type == "number") {
      if (type == "integer" ? !value.is_number_integer() : !value.is_number())
        return fail("is not " + std::string(type == "integer" ? "an integer" : "a number"));
      if (schema.contains("minimum") && value.get<double>() < schema["minimum"].get<double>())
        fail("is below its minimum");
      if (schema.contains("maximum") && value.get<double>() > schema["maximum"].get<double>())
        fail("is above its maximum");
    } else if (type == "boolean") {
      if (!value.is_boolean()) fail("is not a boolean");
    }
    if (schema.contains("enum")) {
      bool listed = false;
      for (const auto& option : schema["enum"]) listed = listed || option == value;
      if (!listed) fail("is " + value.dump() + ", not one of its enum");
    }
  }

  const nlohmann::json root_;
};

// The contract of this source tree, read once per test program.
inline const Contract& contract() {
  static const Contract loaded(std::filesystem::path(TESSERA_SOURCE_DIR) / "docs" / "openapi.yaml");
  return loaded;
}

// An observer for HttpClient::set_observer that fails the running test on any answer the
// contract does not allow.
inline HttpClient::Observer contract_observer() {
  return [](std::string_view method, std::string_view target, const HttpResult& result) {
    for (const std::string& problem : contract().problems(method, target, result))
      ADD_FAILURE() << "not as docs/openapi.yaml says: " << problem;
  };
}

#else

inline HttpClient::Observer contract_observer() {
  static const bool said = [] {
    std::fprintf(stderr, "answers are not checked against docs/openapi.yaml: no yaml-cpp\n");
    return true;
  }();
  (void)said;
  return {};
}

#endif

}  // namespace tessera::test
