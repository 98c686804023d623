// The dashboard (server/web/) spells the contract's names: its job states are the schema's,
// in order, and every state it compares with and every API path it builds is one that
// docs/openapi.yaml defines. A page that drifted from the API would show nothing for a new
// state or ask a path that is not there; this fails first.
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "common/protocol/events.hpp"
#include "common/protocol/jobs.hpp"
#include "common/protocol/workers.hpp"

namespace tessera::protocol {
namespace {

namespace fs = std::filesystem;

const fs::path kWeb = fs::path(TESSERA_SOURCE_DIR) / "server" / "web";

std::string read(const fs::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Every script of the dashboard, by name.
std::vector<std::pair<std::string, std::string>> scripts() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& entry : fs::directory_iterator(kWeb))
    if (entry.path().extension() == ".js")
      out.emplace_back(entry.path().filename().string(), read(entry.path()));
  return out;
}

std::vector<std::string> all_matches(const std::string& text, const std::regex& pattern) {
  std::vector<std::string> out;
  for (std::sregex_iterator at(text.begin(), text.end(), pattern), end; at != end; ++at)
    out.push_back((*at)[1]);
  return out;
}

TEST(DashboardContractTest, TheJobStatesAreTheSchemas) {
  const std::string contract = read(kWeb / "contract.js");
  std::smatch list;
  ASSERT_TRUE(std::regex_search(contract, list, std::regex(R"(JOB_STATES = \[([^\]]*)\])")))
      << contract;
  const std::string items = list[1];
  const std::vector<std::string> states = all_matches(items, std::regex("'([a-z_]+)'"));
  std::vector<std::string> schema;
  for (const auto& [state, name] : kJobStateNames) schema.emplace_back(name);
  EXPECT_EQ(states, schema) << "server/web/contract.js: JOB_STATES";
  const YAML::Node api = YAML::LoadFile(std::string(TESSERA_SOURCE_DIR) + "/docs/openapi.yaml");
  std::vector<std::string> documented;
  for (const auto& item : api["components"]["schemas"]["JobState"]["enum"])
    documented.push_back(item.as<std::string>());
  EXPECT_EQ(states, documented);
}

TEST(DashboardContractTest, EveryStateThePageNamesIsOneOfTheContracts) {
  std::set<std::string> known;
  for (const auto& [state, name] : kJobStateNames) known.emplace(name);
  for (const auto& [state, name] : kWorkerStateNames) known.emplace(name);
  for (const auto& [view, name] : kTileViewNames) known.emplace(name);
  for (const auto& [state, name] : kFrameStateNames) known.emplace(name);
  // `x.state === 'name'`: the API's states. The frame images' own cache
  // (`entry.state`) and a bare `state` (the live indicator's) are the page's own.
  const std::regex compared(
      R"re((?:^|[^\w.?])(?!entry\b)\w+(?:\??\.\w+)*\??\.state\s*[!=]==\s*'([a-z_]+)')re");
  int seen = 0;
  for (const auto& [name, text] : scripts()) {
    for (const std::string& state : all_matches(text, compared)) {
      ++seen;
      EXPECT_TRUE(known.count(state)) << name << ": '" << state << "' is no state of the API";
    }
  }
  EXPECT_GE(seen, 15) << "the page compares with states; the patterns above no longer see them";
}

// A path as a pattern: "{id}" and the page's "${...}" each stand for one segment or more.
std::regex as_pattern(std::string path) {
  static const std::regex parameter(R"(\$\{[^}]*\}|\{[^}]*\})");
  path = std::regex_replace(path, parameter, "\x01");
  std::string out;
  for (const char c : path) {
    if (c == '\x01')
      out += "[^?]+";
    else if (std::string_view(".?+*()[]^$|\\").find(c) != std::string_view::npos)
      out += std::string("\\") + c;
    else
      out += c;
  }
  return std::regex(out);
}

TEST(DashboardContractTest, EveryPathThePageAsksForIsTheContracts) {
  const YAML::Node api = YAML::LoadFile(std::string(TESSERA_SOURCE_DIR) + "/docs/openapi.yaml");
  std::vector<std::string> documented;
  for (const auto& path : api["paths"]) documented.push_back(path.first.as<std::string>());
  // jobPath(id, '/tail') and workerPath(id, '/tail') are /v1/jobs/{id}/tail and
  // /v1/workers/{id}/tail (api.js); any other path is written out whole.
  const std::regex helper(R"re(\b(job|worker)Path\([^,)]+(?:,\s*['`]([^'`]*)['`])?\))re");
  const std::regex literal(R"re(['`](/v1/[^'`?]*)[?'`])re");
  int seen = 0;
  for (const auto& [name, text] : scripts()) {
    std::vector<std::string> asked;
    for (std::sregex_iterator at(text.begin(), text.end(), helper), end; at != end; ++at) {
      std::string tail = (*at)[2];
      tail = tail.substr(0, tail.find('?'));
      asked.push_back(((*at)[1] == "job" ? "/v1/jobs/{id}" : "/v1/workers/{id}") + tail);
    }
    for (const std::string& path : all_matches(text, literal)) asked.push_back(path);
    for (const std::string& path : asked) {
      if (name == "api.js" && path.find("encodeURIComponent") != std::string::npos)
        continue;  // the helpers themselves
      ++seen;
      const std::regex wanted = as_pattern(path);
      bool found = false;
      for (const std::string& route : documented) {
        // A documented route matches where its parameters are filled in as the page fills
        // them: each stands for a segment.
        std::string filled = std::regex_replace(route, std::regex(R"(\{[^}]*\})"), "x");
        found = found || std::regex_match(filled, wanted);
      }
      EXPECT_TRUE(found) << name << ": " << path << " is no path of docs/openapi.yaml";
    }
  }
  EXPECT_GE(seen, 10) << "the page asks for paths; the patterns above no longer see them";
}

}  // namespace
}  // namespace tessera::protocol
