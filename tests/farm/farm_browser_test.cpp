// What a web page the farm's user visits can make a real coordinator do: nothing. Forms
// and text/plain get 415, other sites' pages 403, and a tokenless coordinator on loopback
// answers no name but loopback ones (DNS rebinding); its own pages and the origins named
// with --allowed-origin still may call.
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

TEST(FarmBrowserTest, APageOnAnotherSiteChangesNothing) {
  Farm farm("browser-pages", 0, {"--allowed-origin", "https://dashboard.example:8443"});
  HttpClient http = farm.http(10s);
  const std::string job =
      json{{"name", "from a page"}, {"scene", test::showcase(16, 16, 1, 16)}}.dump();
  // A form post or a text/plain fetch, which a browser sends anywhere without asking.
  EXPECT_EQ(http.request("POST", "/v1/jobs", job, "text/plain").status, 415);
  EXPECT_EQ(http.request("POST", "/v1/jobs", job, "application/x-www-form-urlencoded").status, 415);
  // A JSON post from another site's page (after a preflight no browser would pass).
  const HttpResult cross = http.request("POST", "/v1/jobs", job, "application/json",
                                        {{"Origin", "https://evil.example"}});
  EXPECT_EQ(cross.status, 403) << cross.body;
  EXPECT_EQ(json::parse(cross.body)["error"]["code"], "origin_refused");
  EXPECT_EQ(http.request("GET", "/v1/jobs", "", "", {{"Origin", "https://evil.example"}}).status,
            403);
  EXPECT_EQ(farm.api().jobs("", 10)["jobs"].size(), 0u) << "a page's request made a job";

  // The server's own origin and the one allowed may.
  EXPECT_EQ(http.request("POST", "/v1/jobs", job, "application/json",
                         {{"Origin", "http://127.0.0.1:" + std::to_string(farm.port())}})
                .status,
            201);
  EXPECT_EQ(http.request("POST", "/v1/jobs", job, "application/json",
                         {{"Origin", "https://dashboard.example:8443"}})
                .status,
            201);
  EXPECT_EQ(farm.api().jobs("", 10)["jobs"].size(), 2u);
}

// The page's files are served under /ui/{name}: the style sheet and the script the page
// names, and every module the script imports, each with its type and the page's policy;
// a name that is none of them, or that tries to leave the folder, is nothing.
TEST(FarmBrowserTest, EveryFileThePageLoadsIsServedAndNothingElse) {
  Farm farm("browser-files", 0);
  HttpClient http = farm.http(10s);
  const HttpResult page = http.request("GET", "/");
  ASSERT_EQ(page.status, 200);
  std::vector<std::string> wanted;
  const std::regex linked(R"re((?:src|href)="/ui/([A-Za-z0-9_.-]+)")re");
  for (std::sregex_iterator at(page.body.begin(), page.body.end(), linked), end; at != end; ++at)
    wanted.push_back((*at)[1]);
  ASSERT_EQ(wanted.size(), 2u) << page.body;  // app.css and app.js
  std::set<std::string> served;
  const std::regex imported(R"re(from '\./([A-Za-z0-9_.-]+)')re");
  while (!wanted.empty()) {
    const std::string name = wanted.back();
    wanted.pop_back();
    if (!served.insert(name).second) continue;
    const HttpResult file = http.request("GET", "/ui/" + name);
    ASSERT_EQ(file.status, 200) << name;
    const bool script = name.ends_with(".js");
    EXPECT_EQ(
        file.headers.at("content-type").rfind(script ? "application/javascript" : "text/css", 0),
        0u)
        << name << ": " << file.headers.at("content-type");
    EXPECT_NE(file.headers.at("content-security-policy").find("script-src 'self'"),
              std::string::npos);
    for (std::sregex_iterator at(file.body.begin(), file.body.end(), imported), end; at != end;
         ++at)
      wanted.push_back((*at)[1]);
  }
  EXPECT_GE(served.size(), 10u) << "the script is ES modules, one per view and part";
  for (const char* missing :
       {"/ui/nothing.js", "/ui/index.html", "/ui/..%2Fweb_routes.cpp", "/ui/%2E%2E%2Fapp.js"})
    EXPECT_EQ(http.request("GET", missing).status, 404) << missing;
}

TEST(FarmBrowserTest, ATokenlessCoordinatorAnswersOnlyLoopbackNames) {
  Farm farm("browser-rebinding", 0);
  HttpClient http = farm.http(10s);
  const HttpResult rebound = http.request("GET", "/v1/jobs", "", "", {{"Host", "rebind.example"}});
  EXPECT_EQ(rebound.status, 403) << rebound.body;
  EXPECT_EQ(json::parse(rebound.body)["error"]["code"], "host_refused");
  EXPECT_EQ(http.request("GET", "/v1/jobs", "", "", {{"Host", "localhost"}}).status, 200);
  const HttpResult health = http.request("GET", "/healthz");
  EXPECT_EQ(health.status, 200);
  EXPECT_EQ(json::parse(health.body)["api_token_required"], false) << health.body;
}

TEST(FarmBrowserTest, ACoordinatorWithTokensAnswersAnyName) {
  const auto dir = test::fresh_dir("browser-named-secrets");
  test::write_text(dir / "api", "a-token\n");
  test::write_text(dir / "worker", "w-token\n");
  Farm farm("browser-named", 0,
            {"--api-token-file", (dir / "api").string(), "--worker-token-file",
             (dir / "worker").string()});
  HttpClient http = farm.http(10s);
  http.set_bearer_token("a-token");
  EXPECT_EQ(http.request("GET", "/v1/jobs", "", "", {{"Host", "farm.example"}}).status, 200);
}

}  // namespace
}  // namespace tessera
