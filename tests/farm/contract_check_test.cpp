// The contract check of the farm tests (contract_check.hpp) on answers made up to break
// docs/openapi.yaml, each in one way: a check that passed everything would prove nothing.
#include <gtest/gtest.h>

#include "tests/farm/contract_check.hpp"

namespace tessera {
namespace {

#if TESSERA_CONTRACT_CHECK

HttpResult answer(int status, const std::string& body) { return {status, {}, body}; }

TEST(ContractCheckTest, PassesAnswersAsTheContractSaysAndNamesEveryBreak) {
  const test::Contract& contract = test::contract();
  const std::string worker = R"({"id": "w-1", "name": "n", "host": "h", "threads": 2,
      "state": "idle", "current_job": null, "current_tile": null, "tiles_rendered": 0,
      "last_seen": "2026-12-05T03:00:00Z", "draining": false, "tiles_per_min": 0,
      "rays_per_s": 0})";
  const auto workers = [&](const std::string& one) {
    return answer(200, R"({"workers": [)" + one + "]}");
  };
  EXPECT_EQ(contract.problems("GET", "/v1/workers", workers(worker)), std::vector<std::string>{});
  EXPECT_EQ(contract.problems("GET", "/v1/jobs/j-1", answer(404, R"({"error":
      {"code": "not_found", "message": "no job j-1"}})")),
            std::vector<std::string>{});

  std::string broken = worker;
  broken.replace(broken.find(R"("state": "idle")"), 15, R"("state": "asleep")");
  EXPECT_EQ(contract.problems("GET", "/v1/workers", workers(broken)).size(), 1u) << "an enum";
  broken = worker;
  broken.replace(broken.find(R"("threads": 2)"), 12, R"("threads": "2")");
  EXPECT_EQ(contract.problems("GET", "/v1/workers", workers(broken)).size(), 1u) << "a type";
  broken = worker;
  broken.replace(broken.find(R"("host": "h", )"), 13, "");
  EXPECT_EQ(contract.problems("GET", "/v1/workers", workers(broken)).size(), 1u) << "required";
  broken = worker;
  broken.replace(broken.find(R"("name": "n")"), 11, R"("name": null)");
  EXPECT_EQ(contract.problems("GET", "/v1/workers", workers(broken)).size(), 1u) << "null";
  broken = worker;
  broken.replace(broken.find('{'), 1, R"({"extra": 1, )");
  EXPECT_EQ(contract.problems("GET", "/v1/workers", workers(broken)).size(), 1u) << "unlisted";
  EXPECT_EQ(contract.problems("GET", "/v1/workers", answer(200, "<html>")).size(), 1u);
  EXPECT_EQ(contract.problems("GET", "/v1/workers", answer(418, "")).size(), 1u)
      << "a status the route does not declare";
  EXPECT_EQ(contract.problems("GET", "/v1/nowhere", answer(200, "{}")).size(), 2u)
      << "a route the contract does not have, answered without the error shape";
}

#else

TEST(ContractCheckTest, PassesAnswersAsTheContractSaysAndNamesEveryBreak) {
  GTEST_SKIP() << "yaml-cpp is not installed: answers are not checked against the contract";
}

#endif

}  // namespace
}  // namespace tessera
