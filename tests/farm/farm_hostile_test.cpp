// Hostile and broken input, many at once: every bad request gets a 4xx with the one error
// shape, and afterwards the server serves as before.
#include <atomic>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "common/protocol/limits.hpp"
#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

struct BadRequest {
  const char* what;
  std::string method;
  std::string target;
  std::string body;
  int status;
};

std::vector<BadRequest> bad_requests() {
  const json scene = test::showcase(16, 16, 1, 16);
  const auto with_scene = [&](const std::string& pointer, const json& value) {
    json job = {{"name", "bad"}, {"scene", scene}};
    job[json::json_pointer("/scene" + pointer)] = value;
    return job.dump();
  };
  // 1e999 is valid JSON, but no finite number.
  std::string overflowing = with_scene("/camera/fov_y", 12345.5);
  overflowing.replace(overflowing.find("12345.5"), 7, "1e999");
  std::string deep(100000, '[');
  deep += std::string(100000, ']');
  return {
      {"malformed JSON", "POST", "/v1/jobs", "{\"scene\": {\"image\": ", 400},
      {"truncated JSON", "POST", "/v1/jobs", json{{"scene", scene}}.dump().substr(0, 40), 400},
      {"deeply nested JSON", "POST", "/v1/jobs", "{\"scene\": " + deep + "}", 400},
      {"NaN", "POST", "/v1/jobs", "{\"scene\": {\"image\": {\"width\": NaN}}}", 400},
      {"Infinity", "POST", "/v1/jobs", "{\"scene\": {\"image\": {\"width\": Infinity}}}", 400},
      {"a number too large for a double", "POST", "/v1/jobs", overflowing, 400},
      {"wrong type", "POST", "/v1/jobs", with_scene("/image/width", "wide"), 400},
      {"negative radius", "POST", "/v1/jobs", with_scene("/objects/1/radius", -1), 400},
      {"huge string", "POST", "/v1/jobs",
       json{{"name", std::string(2 << 20, 'x')}, {"scene", scene}}.dump().substr(0, 60) + "\"}",
       400},
      {"a huge name", "POST", "/v1/jobs",
       json{{"name", std::string(1 << 20, 'x')}, {"scene", scene}}.dump(), 400},
      {"a huge worker name", "POST", "/v1/workers", json{{"name", std::string(100000, 'w')}}.dump(),
       400},
      {"a huge array of zeros", "POST", "/v1/jobs",
       with_scene("/objects", json(std::vector<int>(50000, 0))), 400},
      {"not an object", "POST", "/v1/jobs", "[1, 2, 3]", 400},
      {"unknown route", "GET", "/v1/nope", "", 404},
      {"unknown job", "GET", "/v1/jobs/j-nope", "", 404},
      {"traversal in an id", "GET", "/v1/jobs/..%2F..%2Fetc%2Fpasswd/image", "", 404},
      {"bad percent-encoding", "GET", "/v1/jobs/%zz", "", 400},
      {"wrong method", "PATCH", "/v1/jobs", "{}", 405},
      {"upload for no lease", "PUT", "/v1/leases/l-nope/result", std::string(12, '\0'), 409},
      {"upload of a broken size", "PUT", "/v1/leases/l-nope/result", std::string(13, '\0'), 400},
      {"register without a name", "POST", "/v1/workers", "{\"threads\": 2}", 400},
      {"failure report without a tile", "POST", "/v1/leases/l-nope/fail", "{\"error\": \"x\"}",
       400},
      {"claim for no worker", "POST", "/v1/workers/w-nope/claim?wait_s=0", "", 404},
      {"bad wait", "GET", "/v1/jobs/j-nope?wait_s=forever", "", 400},
  };
}

TEST(FarmHostileTest, AStormOfBadRequestsGetsFourHundredsAndTheServerKeepsServing) {
  Farm farm("hostile-storm", 0);
  const std::vector<BadRequest> requests = bad_requests();
  // The lease routes' bad requests come from a registered worker, with its secret: what is
  // tested there is the request, not who sends it.
  const HttpResult registered = farm.http(10s).request(
      "POST", "/v1/workers", json{{"name", "storm"}, {"protocol", kWorkerProtocolVersion}}.dump());
  ASSERT_EQ(registered.status, 201) << registered.body;
  const HttpClient::Headers secret = {
      {"X-Tessera-Worker-Secret", json::parse(registered.body)["secret"].get<std::string>()}};
  std::atomic<int> wrong{0};
  std::atomic<int> answered{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < 8; ++c) {
    clients.emplace_back([&, c] {
      std::mt19937 random(static_cast<unsigned>(c));
      HttpClient http = farm.http(30s);
      for (int i = 0; i < 40; ++i) {
        const BadRequest& bad = requests[random() % requests.size()];
        try {
          // Uploads are pixels; everything else that has a body is JSON.
          const HttpResult result = http.request(
              bad.method, bad.target, bad.body,
              bad.method == "PUT" ? "application/octet-stream" : "application/json", secret);
          const json body = json::parse(result.body, nullptr, false);
          const bool shaped = body.is_object() && body.contains("error") &&
                              body["error"].contains("code") && body["error"].contains("message");
          if (result.status != bad.status || !shaped) {
            ADD_FAILURE() << bad.what << ": " << result.status << " " << result.body.substr(0, 200);
            ++wrong;
          }
          ++answered;
        } catch (const HttpError& e) {
          ADD_FAILURE() << bad.what << ": no answer: " << e.what();
          http = farm.http(30s);
          ++wrong;
        }
      }
    });
  }
  for (std::thread& client : clients) client.join();
  EXPECT_EQ(answered.load(), 8 * 40);
  EXPECT_EQ(wrong.load(), 0);

  // Still serving, and what was stored before is intact.
  HttpClient http = farm.http(10s);
  EXPECT_EQ(http.request("GET", "/healthz").status, 200);
  const json job = farm.api().submit("after the storm", 50, test::showcase(16, 16, 1, 16));
  EXPECT_EQ(job["state"], "queued");
  EXPECT_EQ(farm.api().jobs("", 100)["jobs"].size(), 1u) << "a bad request was stored as a job";
}

}  // namespace
}  // namespace tessera
