// YAML for the tests of deploy/: Kubernetes manifests and the Compose file, read with
// yaml-cpp. A missing key is an undefined node; these helpers turn it into "" or {}, and
// the tests then fail on the value rather than on an exception.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "tests/deploy/deploy_support.hpp"

namespace tessera::test {

inline std::vector<YAML::Node> load_yaml(const std::string& relative) {
  return YAML::LoadAllFromFile(source_path(relative).string());
}

// A missing key gives an invalid node, whose type cannot even be asked: these can.
inline bool is_map(const YAML::Node& node) { return node.IsDefined() && node.IsMap(); }
inline bool is_sequence(const YAML::Node& node) { return node.IsDefined() && node.IsSequence(); }
inline std::size_t size_of(const YAML::Node& node) { return node.IsDefined() ? node.size() : 0; }

inline std::string text_of(const YAML::Node& node) {
  return node.IsDefined() && node.IsScalar() ? node.as<std::string>() : std::string();
}

inline std::vector<std::string> texts_of(const YAML::Node& node) {
  std::vector<std::string> texts;
  if (node.IsDefined() && node.IsSequence())
    for (const YAML::Node& item : node) texts.push_back(text_of(item));
  return texts;
}

// The documents of these files whose `kind` is `kind`.
inline std::vector<YAML::Node> of_kind(const std::vector<YAML::Node>& documents,
                                       const std::string& kind) {
  std::vector<YAML::Node> found;
  for (const YAML::Node& document : documents)
    if (text_of(document["kind"]) == kind) found.push_back(document);
  return found;
}

}  // namespace tessera::test
