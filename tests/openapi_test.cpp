// docs/openapi.yaml is the contract: the server serves exactly the routes it lists.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>

#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include "server/api_routes.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using Route = std::pair<std::string, std::string>;  // METHOD, pattern

// The (method, path) pairs under `paths:`. The file keeps to one layout (paths indented by
// two spaces, methods by four), which this reads; anything else under `paths:` fails.
std::set<Route> openapi_routes(const fs::path& file) {
  std::ifstream in(file);
  std::set<Route> routes;
  const std::regex path_line(R"(^  (/[^:]*):\s*$)");
  const std::regex method_line(R"(^    (get|put|post|delete|patch|head|options):\s*$)");
  bool in_paths = false;
  std::string path;
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
      routes.insert({method, path});
    }
  }
  return routes;
}

TEST(OpenApi, ServerRoutesAndTheContractAgree) {
  const fs::path dir = fs::temp_directory_path() / ("tessera-openapi-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  {
    Store store(dir);
    ManualClock clock;
    Scheduler scheduler(store, clock);
    boost::asio::io_context io;
    LongPolls claims(io);
    LongPolls job_waits(io);
    Router router;
    ApiContext context{scheduler, clock, claims, job_waits, Limits{}, 1 << 20, dir / "tmp"};
    add_health_routes(router);
    add_job_routes(router, context);
    add_worker_routes(router, context);
    const auto served_list = router.routes();
    const std::set<Route> served(served_list.begin(), served_list.end());
    const std::set<Route> documented = openapi_routes(fs::path(TESSERA_SOURCE_DIR) / "docs" / "openapi.yaml");

    EXPECT_GE(documented.size(), 10u) << "docs/openapi.yaml was not read";
    for (const Route& route : served)
      EXPECT_TRUE(documented.contains(route)) << route.first << " " << route.second << " is not in the OpenAPI file";
    for (const Route& route : documented)
      EXPECT_TRUE(served.contains(route)) << route.first << " " << route.second << " is documented but not served";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tessera
