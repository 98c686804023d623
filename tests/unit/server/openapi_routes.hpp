// The routes of docs/openapi.yaml with the role each is for, read for the contract tests.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <utility>

namespace tessera::test {

using Route = std::pair<std::string, std::string>;  // METHOD, pattern

// The (method, path) pairs under `paths:`, each with its x-tessera-role. The file keeps to
// one layout (paths indented by two spaces, methods by four, the role first under its
// method), which this reads.
inline std::map<Route, std::string> openapi_routes(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::map<Route, std::string> routes;
  const std::regex path_line(R"(^  (/[^:]*):\s*$)");
  const std::regex method_line(R"(^    (get|put|post|delete|patch|head|options):\s*$)");
  const std::regex role_line(R"(^      x-tessera-role: (\w+)\s*$)");
  bool in_paths = false;
  std::string path;
  std::optional<Route> last;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("paths:", 0) == 0) {
      in_paths = true;
      continue;
    }
    if (in_paths && !line.empty() && line[0] != ' ') break;  // the next top-level key
    std::smatch m;
    if (!in_paths) continue;
    if (std::regex_match(line, m, path_line)) {
      path = m[1];
    } else if (std::regex_match(line, m, method_line)) {
      std::string method = m[1];
      std::transform(method.begin(), method.end(), method.begin(), ::toupper);
      last = Route{method, path};
      routes[*last] = "";
    } else if (last && std::regex_match(line, m, role_line)) {
      routes[*last] = m[1];
      last.reset();
    }
  }
  return routes;
}

}  // namespace tessera::test
