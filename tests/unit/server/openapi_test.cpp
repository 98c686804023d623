// docs/openapi.yaml is the contract: the server serves exactly the routes it lists.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>

#include <gtest/gtest.h>
#include <boost/asio/io_context.hpp>

#include "server/api/api_routes.hpp"
#include "server/api/asset_store.hpp"
#include "server/farm/sqlite_store.hpp"
#include "tests/unit/server/openapi_routes.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using test::openapi_routes;
using test::Route;

TEST(OpenApiTest, ServerRoutesAndTheContractAgree) {
  const fs::path dir =
      fs::temp_directory_path() / ("tessera-openapi-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  {
    SqliteStore store(dir);
    ManualClock clock;
    Scheduler scheduler(store, clock);
    boost::asio::io_context io;
    LongPolls claims(io);
    LongPolls job_waits(io);
    Router router;
    ApiContext context{scheduler, clock, claims, job_waits, Limits{}, 1 << 20, dir / "tmp"};
    AssetStore assets(dir / "assets", 1 << 20);
    context.assets = &assets;
    add_api_routes(router, context);
    const auto served_list = router.routes();
    const std::set<Route> served(served_list.begin(), served_list.end());
    const auto documented = openapi_routes(fs::path(TESSERA_SOURCE_DIR) / "docs" / "openapi.yaml");

    EXPECT_GE(documented.size(), 10u) << "docs/openapi.yaml was not read";
    for (const Route& route : served)
      EXPECT_TRUE(documented.contains(route))
          << route.first << " " << route.second << " is not in the OpenAPI file";
    for (const auto& [route, role] : documented) {
      EXPECT_TRUE(served.contains(route))
          << route.first << " " << route.second << " is documented but not served";
      // The role the server checks is the one the contract names ("" is public).
      const auto served_role = router.role_of(route.first, route.second);
      if (served_role) {
        EXPECT_EQ(served_role->empty() ? "public" : *served_role, role)
            << route.first << " " << route.second;
      }
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tessera
