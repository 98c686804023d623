// The worker protocol and the error contract of docs/api.md, spoken raw over HTTP to a real
// tessera-server with no workers of its own: the test plays the worker, so it can do what a
// real worker only does by accident (stop heartbeating, upload late, upload twice, upload
// the wrong size) and check that the coordinator fences every such result out.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <future>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <tuple>

#include <gtest/gtest.h>

#include "common/protocol/limits.hpp"
#include "common/protocol/workers.hpp"
#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

using Clock = std::chrono::steady_clock;

// One tile: the whole 16x16 image.
json one_tile_scene() { return test::showcase(16, 16, 1, 16); }

// `width * height` pixels of float32 RGB, every channel `value`, as the upload body.
std::string tile_body(int width, int height, float value) {
  const std::vector<float> pixels(static_cast<std::size_t>(width) * height * 3, value);
  return std::string(reinterpret_cast<const char*>(pixels.data()), pixels.size() * sizeof(float));
}

// Checks the one error shape of docs/api.md: the status and {"error": {"code", "message"}}.
::testing::AssertionResult is_error(const HttpResult& result, int status, const std::string& code) {
  if (result.status != status)
    return ::testing::AssertionFailure()
           << "status " << result.status << " instead of " << status << ": " << result.body;
  const auto type = result.headers.find("content-type");
  if (type == result.headers.end() || type->second.find("application/json") == std::string::npos)
    return ::testing::AssertionFailure() << "error answer " << status << " is not JSON";
  const json body = json::parse(result.body, nullptr, false);
  if (body.is_discarded() || !body.is_object() || !body.contains("error") ||
      !body["error"].is_object())
    return ::testing::AssertionFailure() << "no {\"error\": {...}} body: " << result.body;
  const json& error = body["error"];
  if (!error.contains("code") || !error["code"].is_string() || error["code"] != code)
    return ::testing::AssertionFailure() << "code is not \"" << code << "\": " << result.body;
  if (!error.contains("message") || !error["message"].is_string() ||
      error["message"].get<std::string>().empty())
    return ::testing::AssertionFailure() << "no message: " << result.body;
  return ::testing::AssertionSuccess();
}

// The test's own worker: registered on construction, one keep-alive connection; every
// later request proves it with the secret its registration gave.
class RawWorker {
 public:
  RawWorker(const std::string& url, const std::string& name) : url_(url), http_(url, 30s) {
    const HttpResult reply = http_.request(
        "POST", "/v1/workers",
        json{{"name", name}, {"host", "test"}, {"threads", 1}, {"protocol", kWorkerProtocolVersion}}
            .dump());
    if (reply.status != 201) throw std::runtime_error("register answered " + reply.body);
    registration_ = json::parse(reply.body);
    id_ = registration_["id"];
    secret_ = registration_["secret"];
  }

  const std::string& id() const { return id_; }
  const std::string& secret() const { return secret_; }
  const json& registration() const { return registration_; }
  HttpResult leave() { return send("DELETE", "/v1/workers/" + id_); }

  HttpResult claim(double wait_s, const std::string& more_query = "") {
    return send("POST",
                "/v1/workers/" + id_ + "/claim?wait_s=" + std::to_string(wait_s) + more_query);
  }
  HttpResult heartbeat(const std::string& lease) {
    return send("POST", "/v1/leases/" + lease + "/heartbeat");
  }
  HttpResult upload(const std::string& lease, std::string body, std::uint64_t rays = 100) {
    return send("PUT", "/v1/leases/" + lease + "/result", std::move(body),
                "application/octet-stream", {{"X-Tessera-Rays", std::to_string(rays)}});
  }
  // Some of a batch lease's tiles in one request, as tessera-worker sends them.
  HttpResult upload_tiles(const std::string& lease, const std::string& tiles, std::string body,
                          const std::string& rays) {
    return send("PUT", "/v1/leases/" + lease + "/result", std::move(body),
                "application/octet-stream", {{"X-Tessera-Tiles", tiles}, {"X-Tessera-Rays", rays}});
  }
  // Any request, with this worker's secret.
  HttpResult send(std::string_view method, const std::string& target, std::string body = {},
                  std::string_view content_type = "application/json",
                  HttpClient::Headers headers = {}) {
    headers.emplace_back("X-Tessera-Worker-Secret", secret_);
    return http_.request(method, target, std::move(body), content_type, headers);
  }
  // A new connection, as after a network blip: the worker id is all that carries over.
  void reconnect() { http_ = HttpClient(url_, 30s); }

 private:
  std::string url_;
  HttpClient http_;
  json registration_;
  std::string id_;
  std::string secret_;
};

// The job's image so far as EXR bytes; partial, so it is served before completion too.
std::string exr_bytes(HttpClient& http, const std::string& job) {
  const HttpResult reply = http.request("GET", "/v1/jobs/" + job + "/image?format=exr&partial=1");
  EXPECT_EQ(reply.status, 200) << reply.body;
  return reply.body;
}

Image decode_exr(const Farm& farm, const std::string& bytes) {
  static int counter = 0;
  const fs::path path = farm.dir() / ("decoded-" + std::to_string(++counter) + ".exr");
  test::write_text(path, bytes);
  return read_image(path);
}

// The same pixels: EXR bytes themselves differ by the time they were written at.
::testing::AssertionResult same_image(const Farm& farm, const std::string& a,
                                      const std::string& b) {
  return test::same_pixels(decode_exr(farm, a), decode_exr(farm, b));
}

bool all_pixels_are(const Image& image, float value) {
  for (const float channel : image.pixels())
    if (channel != value) return false;
  return !image.pixels().empty();
}

json worker_info(Farm& farm, const std::string& id) {
  const json reply = farm.api().workers();
  for (const json& worker : reply["workers"])
    if (worker["id"] == id) return worker;
  return nullptr;
}

TEST(FarmProtocolTest, ClaimHeartbeatReconnectUploadAndDuplicate) {
  Farm farm("proto-basic", 0);
  HttpClient http = farm.http(10s);
  RawWorker worker(farm.url(), "raw");
  EXPECT_EQ(worker.registration()["heartbeat_interval_s"], 5.0);  // the documented defaults
  EXPECT_EQ(worker.registration()["lease_timeout_s"], 30.0);

  // Nothing queued: the long poll holds the request for wait_s, then says 204.
  const auto poll_start = Clock::now();
  EXPECT_EQ(worker.claim(0.2).status, 204);
  const auto polled = Clock::now() - poll_start;
  EXPECT_GE(polled, 190ms);
  EXPECT_LT(polled, 5s);

  const json job = farm.api().submit("one tile", 50, one_tile_scene());
  const std::string job_id = job["id"];
  const HttpResult claimed = worker.claim(5);
  ASSERT_EQ(claimed.status, 200) << claimed.body;
  const json lease = json::parse(claimed.body);
  const std::string lease_id = lease["id"];
  EXPECT_FALSE(lease_id.empty());
  EXPECT_EQ(lease["job_id"], job_id);
  EXPECT_EQ(lease["tiles"],
            json::array({{{"index", 0}, {"x", 0}, {"y", 0}, {"width", 16}, {"height", 16}}}));
  EXPECT_GT(lease["expires_in_s"].get<double>(), 0);
  EXPECT_LE(lease["expires_in_s"].get<double>(), 30);
  // The scene a worker renders is the one submitted, fetched by its digest.
  const HttpResult scene =
      worker.send("GET", "/v1/scenes/" + lease["scene_digest"].get<std::string>());
  ASSERT_EQ(scene.status, 200);
  EXPECT_EQ(json::parse(scene.body), one_tile_scene());
  const json info = worker_info(farm, worker.id());
  EXPECT_EQ(info["state"], "rendering");
  EXPECT_EQ(info["current_job"], job_id);
  EXPECT_EQ(farm.api().job(job_id)["state"], "running");

  const HttpResult beat = worker.heartbeat(lease_id);
  ASSERT_EQ(beat.status, 200) << beat.body;
  EXPECT_EQ(json::parse(beat.body)["id"], lease_id);

  // After a reconnect the worker asks again while still holding its lease: it gets the
  // same lease back, not a second tile and not a new fencing token.
  worker.reconnect();
  const HttpResult again = worker.claim(0);
  ASSERT_EQ(again.status, 200) << again.body;
  EXPECT_EQ(json::parse(again.body)["id"], lease_id);

  // Wrong sizes are refused and leave the lease live.
  EXPECT_TRUE(is_error(worker.upload(lease_id, tile_body(16, 15, 0.5f)), 400, "wrong_size"));
  EXPECT_TRUE(is_error(worker.upload(lease_id, tile_body(16, 16, 0.5f) + "x"), 400, "wrong_size"));
  EXPECT_TRUE(is_error(worker.upload(lease_id, ""), 400, "wrong_size"));
  // Values no render gives are refused, naming the tile and the pixel, with or without
  // X-Tessera-Tiles.
  for (const float impossible :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -0.25f}) {
    std::string body = tile_body(16, 16, 0.5f);
    std::memcpy(body.data() + (17 * 3 + 1) * sizeof(float), &impossible, sizeof(float));
    const HttpResult whole = worker.upload(lease_id, body);
    EXPECT_TRUE(is_error(whole, 400, "invalid_pixels")) << impossible;
    EXPECT_NE(whole.body.find("pixel 17 (channel 1)"), std::string::npos) << whole.body;
    const HttpResult named = worker.upload_tiles(lease_id, "0", body, "100");
    EXPECT_TRUE(is_error(named, 400, "invalid_pixels")) << impossible;
    EXPECT_NE(named.body.find("tile 0 holds"), std::string::npos) << named.body;
  }
  EXPECT_EQ(worker.heartbeat(lease_id).status, 200);
  EXPECT_EQ(farm.api().job(job_id)["tiles"]["done"], 0);

  const HttpResult accepted = worker.upload(lease_id, tile_body(16, 16, 0.5f), 1234);
  ASSERT_EQ(accepted.status, 200) << accepted.body;
  EXPECT_EQ(json::parse(accepted.body)["status"], "accepted");
  const json done = farm.api().job(job_id);
  EXPECT_EQ(done["state"], "completed");
  EXPECT_EQ(done["stats"]["rays"], 1234);
  const std::string image = exr_bytes(http, job_id);
  EXPECT_TRUE(all_pixels_are(decode_exr(farm, image), 0.5f));
  EXPECT_EQ(worker_info(farm, worker.id())["tiles_rendered"], 1);
  EXPECT_EQ(worker_info(farm, worker.id())["state"], "idle");

  // The same lease delivering again (a retried upload) changes nothing, even with other pixels.
  const HttpResult duplicate = worker.upload(lease_id, tile_body(16, 16, 0.25f), 99);
  ASSERT_EQ(duplicate.status, 200) << duplicate.body;
  EXPECT_EQ(json::parse(duplicate.body)["status"], "duplicate");
  EXPECT_TRUE(same_image(farm, exr_bytes(http, job_id), image));
  EXPECT_EQ(farm.api().job(job_id)["stats"]["rays"], 1234);
  EXPECT_EQ(worker_info(farm, worker.id())["tiles_rendered"], 1);
  // A delivered lease is over.
  EXPECT_TRUE(is_error(worker.heartbeat(lease_id), 410, "lease_lost"));
}

TEST(FarmProtocolTest, ABatchLeaseDeliversItsTilesInGroups) {
  Farm farm("proto-batch", 0);
  HttpClient http = farm.http(10s);
  RawWorker worker(farm.url(), "batch");
  const std::string job_id = farm.api().submit("batch", 50, test::showcase(64, 32, 1, 16))["id"];

  for (const char* bad : {"&max_tiles=0", "&max_tiles=257", "&max_tiles=two", "&max_tiles=1,2"})
    EXPECT_TRUE(is_error(worker.claim(0, bad), 400, "invalid_request")) << bad;
  // 8 tiles and one worker: a claim gets at most half of them, so that workers joining
  // later still find some.
  const HttpResult claimed = worker.claim(5, "&max_tiles=100");
  ASSERT_EQ(claimed.status, 200) << claimed.body;
  const json lease = json::parse(claimed.body);
  const std::string lease_id = lease["id"];
  ASSERT_EQ(lease["tiles"].size(), 4u) << lease.dump();
  std::vector<int> tiles;
  for (const json& tile : lease["tiles"]) {
    EXPECT_EQ(tile["width"], 16);
    tiles.push_back(tile["index"]);
  }
  // The four middle tiles of the 4x2 grid, centre-first.
  EXPECT_EQ(std::set<int>(tiles.begin(), tiles.end()), (std::set<int>{1, 2, 5, 6}));
  EXPECT_EQ(farm.api().job(job_id)["tiles"]["rendering"], 4);
  const auto index = [&](int i) { return std::to_string(tiles[static_cast<std::size_t>(i)]); };

  // Two tiles in one upload, each its own value.
  const HttpResult first =
      worker.upload_tiles(lease_id, index(0) + "," + index(1),
                          tile_body(16, 16, 1.0f) + tile_body(16, 16, 2.0f), "10,20");
  ASSERT_EQ(first.status, 200) << first.body;
  EXPECT_EQ(json::parse(first.body)["status"], "accepted");
  json job = farm.api().job(job_id);
  EXPECT_EQ(job["tiles"]["done"], 2);
  EXPECT_EQ(job["tiles"]["rendering"], 2);
  EXPECT_EQ(job["stats"]["rays"], 30);
  // What is still owed comes back on a heartbeat, and on a re-claim.
  const HttpResult beat = worker.heartbeat(lease_id);
  ASSERT_EQ(beat.status, 200) << beat.body;
  EXPECT_EQ(json::parse(beat.body)["tiles"].size(), 2u);
  EXPECT_EQ(json::parse(worker.claim(0).body)["tiles"], json::parse(beat.body)["tiles"]);

  // Refused, and nothing stored: a tile the lease does not hold, one named twice, a
  // missing ray count, the wrong size.
  const std::string before = exr_bytes(http, job_id);
  EXPECT_TRUE(is_error(worker.upload_tiles(lease_id, "0", tile_body(16, 16, 9.0f), "1"), 400,
                       "wrong_tile"));
  EXPECT_TRUE(
      is_error(worker.upload_tiles(lease_id, index(2) + "," + index(2),
                                   tile_body(16, 16, 9.0f) + tile_body(16, 16, 9.0f), "1,1"),
               400, "wrong_tile"));
  EXPECT_TRUE(is_error(worker.upload_tiles(lease_id, index(2) + "," + index(3),
                                           tile_body(16, 16, 9.0f) + tile_body(16, 16, 9.0f), "1"),
                       400, "invalid_request"));
  EXPECT_TRUE(is_error(worker.upload_tiles(lease_id, index(2), tile_body(16, 8, 9.0f), "1"), 400,
                       "wrong_size"));
  EXPECT_TRUE(is_error(worker.upload_tiles(lease_id, "x", tile_body(16, 16, 9.0f), "1"), 400,
                       "invalid_request"));
  EXPECT_TRUE(same_image(farm, exr_bytes(http, job_id), before));

  // A retried group beside a new tile: the repeat is ignored, the new tile stored.
  const HttpResult mixed =
      worker.upload_tiles(lease_id, index(1) + "," + index(2),
                          tile_body(16, 16, 7.0f) + tile_body(16, 16, 3.0f), "20,30");
  ASSERT_EQ(mixed.status, 200) << mixed.body;
  EXPECT_EQ(json::parse(mixed.body)["status"], "accepted");
  const HttpResult repeat = worker.upload_tiles(lease_id, index(2), tile_body(16, 16, 7.0f), "30");
  ASSERT_EQ(repeat.status, 200) << repeat.body;
  EXPECT_EQ(json::parse(repeat.body)["status"], "duplicate");
  ASSERT_EQ(worker.upload_tiles(lease_id, index(3), tile_body(16, 16, 4.0f), "40").status, 200);
  // Every tile delivered: the lease is over and the worker idle.
  EXPECT_TRUE(is_error(worker.heartbeat(lease_id), 410, "lease_lost"));
  EXPECT_EQ(worker_info(farm, worker.id())["state"], "idle");
  EXPECT_EQ(worker_info(farm, worker.id())["tiles_rendered"], 4);
  job = farm.api().job(job_id);
  EXPECT_EQ(job["tiles"]["done"], 4);
  EXPECT_EQ(job["stats"]["rays"], 100);

  // Each tile holds the value of its first accepted upload.
  const Image image = decode_exr(farm, exr_bytes(http, job_id));
  for (int i = 0; i < 4; ++i) {
    const int tile = tiles[static_cast<std::size_t>(i)];
    const int x = tile % 4 * 16 + 8;
    const int y = tile / 4 * 16 + 8;
    EXPECT_EQ(image.pixels()[(static_cast<std::size_t>(y) * 64 + x) * 3], static_cast<float>(i + 1))
        << "tile " << tile;
  }
}

TEST(FarmProtocolTest, AClaimParkedOnAnEmptyQueueWakesWhenAJobArrives) {
  Farm farm("proto-wake", 0);
  RawWorker worker(farm.url(), "parked");
  const auto start = Clock::now();
  auto parked = std::async(std::launch::async, [&] { return worker.claim(20); });
  // Submit only once the claim is parked, so the wake-up is what is measured.
  ASSERT_EQ(parked.wait_for(300ms), std::future_status::timeout) << "the claim did not wait";
  const json job = farm.api().submit("wake", 50, one_tile_scene());
  const HttpResult claimed = parked.get();
  ASSERT_EQ(claimed.status, 200) << claimed.body;
  EXPECT_EQ(json::parse(claimed.body)["job_id"], job["id"]);
  EXPECT_LT(Clock::now() - start, 10s) << "the claim waited for its timeout instead of the job";
}

TEST(FarmProtocolTest, AStatusRequestWithWaitSAnswersWhenTheJobFinishes) {
  Farm farm("proto-job-wait", 0);
  HttpClient http = farm.http(30s);
  RawWorker worker(farm.url(), "finisher");
  const std::string job_id = farm.api().submit("waited", 50, one_tile_scene())["id"];
  for (const char* bad : {"-1", "61", "soon", "1x"})
    EXPECT_TRUE(is_error(http.request("GET", "/v1/jobs/" + job_id + "?wait_s=" + bad), 400,
                         "invalid_request"))
        << bad;
  EXPECT_TRUE(is_error(http.request("GET", "/v1/jobs/j-missing?wait_s=5"), 404, "not_found"));

  // Not finished within wait_s: the status as it is, after the wait.
  const auto start = Clock::now();
  const HttpResult unfinished = http.request("GET", "/v1/jobs/" + job_id + "?wait_s=0.3");
  EXPECT_GE(Clock::now() - start, 290ms);
  ASSERT_EQ(unfinished.status, 200) << unfinished.body;
  EXPECT_EQ(json::parse(unfinished.body)["state"], "queued");

  // Parked, then woken by the result that completes the job.
  auto parked = std::async(std::launch::async, [&] {
    HttpClient waiting = farm.http(30s);
    return waiting.request("GET", "/v1/jobs/" + job_id + "?wait_s=20");
  });
  ASSERT_EQ(parked.wait_for(300ms), std::future_status::timeout) << "the status did not wait";
  const HttpResult claimed = worker.claim(5);
  ASSERT_EQ(claimed.status, 200) << claimed.body;
  const auto delivered_at = Clock::now();
  ASSERT_EQ(worker.upload(json::parse(claimed.body)["id"], tile_body(16, 16, 0.5f)).status, 200);
  const HttpResult finished = parked.get();
  EXPECT_LT(Clock::now() - delivered_at, 5s)
      << "the status waited for its timeout instead of the job";
  ASSERT_EQ(finished.status, 200) << finished.body;
  EXPECT_EQ(json::parse(finished.body)["state"], "completed");
  // A finished job answers at once.
  const auto again = Clock::now();
  EXPECT_EQ(json::parse(http.request("GET", "/v1/jobs/" + job_id + "?wait_s=20").body)["state"],
            "completed");
  EXPECT_LT(Clock::now() - again, 5s);
}

TEST(FarmProtocolTest, AnExpiredLeaseIsReassignedAndItsLateResultIsRefused) {
  Farm farm("proto-expiry", 0, {"--lease-timeout", "1", "--heartbeat-interval", "0.2"});
  HttpClient http = farm.http(10s);
  RawWorker slow(farm.url(), "slow");
  RawWorker rescuer(farm.url(), "rescuer");
  EXPECT_EQ(slow.registration()["heartbeat_interval_s"], 0.2);
  EXPECT_EQ(slow.registration()["lease_timeout_s"], 1.0);

  const std::string job_id = farm.api().submit("expiry", 50, one_tile_scene())["id"];
  const HttpResult first = slow.claim(5);
  ASSERT_EQ(first.status, 200) << first.body;
  const auto granted = Clock::now();
  const json slow_lease = json::parse(first.body);

  // `slow` never heartbeats. The rescuer's claim waits until the lease times out and then
  // gets the same tile under a new lease id, the fencing token that tells the two apart.
  const HttpResult second = rescuer.claim(20);
  ASSERT_EQ(second.status, 200) << second.body;
  EXPECT_GE(Clock::now() - granted, 900ms) << "the tile was given away before its lease timed out";
  const json rescuer_lease = json::parse(second.body);
  EXPECT_NE(rescuer_lease["id"], slow_lease["id"]);
  EXPECT_EQ(rescuer_lease["job_id"], job_id);
  EXPECT_EQ(rescuer_lease["tiles"], slow_lease["tiles"]);
  EXPECT_EQ(worker_info(farm, slow.id())["state"], "idle");

  // The rescuer keeps its lease alive as tessera-worker does, every heartbeat interval,
  // however long the checks below take on a busy machine.
  std::atomic<bool> checked{false};
  std::thread beating([&, lease = rescuer_lease["id"].get<std::string>()] {
    HttpClient beats = farm.http(10s);
    while (!checked) {
      beats.request("POST", "/v1/leases/" + lease + "/heartbeat", {}, "application/json",
                    {{"X-Tessera-Worker-Secret", rescuer.secret()}});
      std::this_thread::sleep_for(200ms);
    }
  });
  // The slow worker learns it lost the tile, and its late result is refused.
  EXPECT_TRUE(is_error(slow.heartbeat(slow_lease["id"]), 410, "lease_lost"));
  const std::string before = exr_bytes(http, job_id);
  EXPECT_TRUE(is_error(slow.upload(slow_lease["id"], tile_body(16, 16, 1.0f)), 409, "lease_lost"));
  EXPECT_TRUE(same_image(farm, exr_bytes(http, job_id), before));
  EXPECT_TRUE(all_pixels_are(decode_exr(farm, before), 0.0f));
  EXPECT_EQ(farm.api().job(job_id)["tiles"]["done"], 0);

  // The current holder delivers; the stale one still cannot overwrite it afterwards.
  checked = true;
  beating.join();
  EXPECT_EQ(rescuer.heartbeat(rescuer_lease["id"]).status, 200);
  const HttpResult accepted = rescuer.upload(rescuer_lease["id"], tile_body(16, 16, 0.25f));
  ASSERT_EQ(accepted.status, 200) << accepted.body;
  EXPECT_EQ(json::parse(accepted.body)["status"], "accepted");
  const std::string delivered = exr_bytes(http, job_id);
  EXPECT_TRUE(all_pixels_are(decode_exr(farm, delivered), 0.25f));
  EXPECT_TRUE(is_error(slow.upload(slow_lease["id"], tile_body(16, 16, 1.0f)), 409, "lease_lost"));
  EXPECT_TRUE(same_image(farm, exr_bytes(http, job_id), delivered));
  EXPECT_EQ(farm.api().job(job_id)["state"], "completed");
  EXPECT_EQ(worker_info(farm, slow.id())["tiles_rendered"], 0);
  EXPECT_EQ(worker_info(farm, rescuer.id())["tiles_rendered"], 1);
}

TEST(FarmProtocolTest, CancelWithdrawsTheLease) {
  Farm farm("proto-cancel", 0);
  RawWorker worker(farm.url(), "canceled");
  const std::string job_id = farm.api().submit("to cancel", 50, one_tile_scene())["id"];
  const HttpResult claimed = worker.claim(5);
  ASSERT_EQ(claimed.status, 200) << claimed.body;
  const std::string lease_id = json::parse(claimed.body)["id"];
  ASSERT_EQ(worker.heartbeat(lease_id).status, 200);

  EXPECT_EQ(farm.api().cancel(job_id)["state"], "canceled");
  EXPECT_TRUE(is_error(worker.heartbeat(lease_id), 410, "lease_lost"));
  EXPECT_TRUE(is_error(worker.upload(lease_id, tile_body(16, 16, 0.5f)), 409, "lease_lost"));
  EXPECT_EQ(worker_info(farm, worker.id())["state"], "idle");
  EXPECT_EQ(farm.api().job(job_id)["tiles"]["done"], 0);
  // A canceled job's tiles are not handed out again.
  EXPECT_EQ(worker.claim(0.2).status, 204);
}

// What a raw socket gets back: just enough HTTP/1.1 parsing for one answer.
struct RawAnswer {
  int status = 0;
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;
};

// Sends `head` (request line and headers, no body) and reads one answer. The server must
// answer from the headers alone; a server that waited for the body would time out here.
RawAnswer send_head_only(int port, const std::string& head) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw std::runtime_error("socket failed");
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  const timeval timeout{10, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0)
    throw std::runtime_error("connect failed");
  if (::send(fd, head.data(), head.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(head.size()))
    throw std::runtime_error("send failed");

  std::string received;
  std::size_t header_end = std::string::npos;
  std::size_t body_length = std::string::npos;
  char buffer[4096];
  while (true) {
    if (header_end != std::string::npos && body_length != std::string::npos &&
        received.size() >= header_end + 4 + body_length)
      break;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;  // closed, or no answer within the timeout
    received.append(buffer, static_cast<std::size_t>(n));
    if (header_end == std::string::npos &&
        (header_end = received.find("\r\n\r\n")) != std::string::npos) {
      const std::string lower = [&] {
        std::string text = received.substr(0, header_end);
        for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        return text;
      }();
      const auto length = lower.find("\r\ncontent-length:");
      if (length != std::string::npos) body_length = std::stoul(lower.substr(length + 17));
    }
  }
  RawAnswer answer;
  if (header_end == std::string::npos) return answer;
  std::istringstream lines(received.substr(0, header_end));
  std::string line;
  std::getline(lines, line);
  if (line.rfind("HTTP/1.1 ", 0) == 0) answer.status = std::stoi(line.substr(9, 3));
  while (std::getline(lines, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    std::string value = line.substr(colon + 1);
    while (!value.empty() && (value.front() == ' ')) value.erase(0, 1);
    while (!value.empty() && (value.back() == '\r' || value.back() == ' ')) value.pop_back();
    answer.headers[name] = value;
  }
  answer.body = received.substr(header_end + 4);
  return answer;
}

TEST(FarmProtocolTest, AJobOverTheServersLimitsIsRefusedWith422NamingTheLimit) {
  Farm farm("proto-limits", 0,
            {"--max-samples", "8", "--max-pixels", "10000", "--max-job-bytes", "100000"});
  HttpClient http = farm.http(10s);
  const auto submit = [&](const json& scene) {
    return http.request("POST", "/v1/jobs", json{{"name", "big"}, {"scene", scene}}.dump());
  };
  const HttpResult samples = submit(test::showcase(16, 16, 16, 16));
  ASSERT_TRUE(is_error(samples, 422, "over_limit"));
  json error = json::parse(samples.body)["error"];
  EXPECT_EQ(error["limit"], "max_samples_per_pixel");
  EXPECT_EQ(error["limit_value"], 8);
  EXPECT_EQ(error["path"], "/scene/render/samples_per_pixel");
  EXPECT_NE(error["message"].get<std::string>().find("got 16"), std::string::npos) << error.dump();

  const HttpResult pixels = submit(test::showcase(200, 100, 1, 16));
  ASSERT_TRUE(is_error(pixels, 422, "over_limit"));
  error = json::parse(pixels.body)["error"];
  EXPECT_EQ(error["limit"], "max_pixels");
  EXPECT_EQ(error["limit_value"], 10000);
  EXPECT_EQ(error["path"], "/scene/image");

  // The body limit is a flag too, and answered from the headers.
  json padded = test::showcase(16, 16, 1, 16);
  padded["materials"]["padding"] = {{"diffuse", 0.5}};
  const std::string body = json{{"scene", padded}, {"name", std::string(150000, 'x')}}.dump();
  EXPECT_TRUE(is_error(http.request("POST", "/v1/jobs", body), 413, "body_too_large"));

  // Within the limits, accepted; the CLI reports the refusal as one (exit 1), naming the limit.
  EXPECT_EQ(submit(test::showcase(16, 16, 8, 16)).status, 201);
  const fs::path scene_file = farm.dir() / "over.json";
  test::write_text(scene_file, test::showcase(16, 16, 16, 16).dump());
  const test::CliRun cli =
      test::run_cli(farm.dir(), {"--server", farm.url(), "submit", scene_file.string()});
  EXPECT_EQ(cli.exit_code, 1) << cli.output;
  EXPECT_NE(cli.output.find("limit max_samples_per_pixel"), std::string::npos) << cli.output;
}

TEST(FarmProtocolTest, AnimatedScenesAreCheckedWholeAndTheirFrameListsToo) {
  Farm farm("proto-animation", 0, {"--max-frames", "100"});
  HttpClient http = farm.http(10s);
  const auto submit = [&](const json& scene, std::optional<std::string> frames = std::nullopt) {
    json body{{"name", "anim"}, {"scene", scene}};
    if (frames) body["frames"] = *frames;
    return http.request("POST", "/v1/jobs", body.dump());
  };
  json scene = test::showcase(16, 16, 1, 16);
  scene["animation"] = {{"frames", {1, 20}}};
  scene["camera"]["eye"] = {{"keys", {{1, {0, 2, 8}}, {20, {4, 2, 6}}}}};
  const HttpResult animated = submit(scene);
  ASSERT_EQ(animated.status, 201) << animated.body;
  const json job = json::parse(animated.body);
  EXPECT_EQ(job["frames"]["list"], "1-20");
  EXPECT_EQ(job["frames"]["total"], 20);
  EXPECT_EQ(job["tiles"]["total"], 20) << "one 16-pixel tile a frame";
  EXPECT_EQ(job["frames"]["current"], 1);
  const HttpResult some = submit(scene, "2-20x6,7");
  ASSERT_EQ(some.status, 201) << some.body;
  EXPECT_EQ(json::parse(some.body)["frames"]["list"], "2,7,8-20x6");

  // A frame list is read against the scene's range, its errors at /frames.
  for (const std::string bad : {"0-5", "1-x", "", "21", "5-3"}) {
    const HttpResult refused = submit(scene, bad);
    ASSERT_TRUE(is_error(refused, 400, "invalid_request")) << bad << ": " << refused.body;
    EXPECT_EQ(json::parse(refused.body)["error"]["path"], "/frames") << bad;
  }
  // A still is frame 0 only.
  EXPECT_EQ(submit(test::showcase(16, 16, 1, 16), "0").status, 201);
  const HttpResult still = submit(test::showcase(16, 16, 1, 16), "3");
  ASSERT_TRUE(is_error(still, 400, "invalid_request")) << still.body;
  EXPECT_NE(json::parse(still.body)["error"]["message"].get<std::string>().find("no \"animation\""),
            std::string::npos)
      << still.body;
  // An animation holds no more tiles than the largest still: 100 frames of 62,500 tiles.
  json huge = scene;
  huge["image"] = {{"width", 2000}, {"height", 2000}};
  huge["render"]["tile_size"] = 8;
  huge["animation"]["frames"] = {1, 100};
  const HttpResult too_many = submit(huge);
  ASSERT_TRUE(is_error(too_many, 422, "over_limit")) << too_many.body;
  EXPECT_EQ(json::parse(too_many.body)["error"]["limit"], "max_job_tiles");

  // Every frame of every track is checked, objects too, each kept apart as the
  // coordinator reads them: a scale that passes through zero at frame 11.
  json flat = scene;
  flat["animation"]["frames"] = {1, 21};
  flat["objects"][0]["transform"] = json::array({{{"scale", {{"keys", {{1, 1}, {21, -1}}}}}}});
  const HttpResult squashed = submit(flat);
  ASSERT_TRUE(is_error(squashed, 400, "invalid_scene")) << squashed.body;
  const json error = json::parse(squashed.body)["error"];
  EXPECT_EQ(error["path"], "/scene/objects/0/transform/0/scale");
  EXPECT_NE(error["message"].get<std::string>().find("at frame 11, must be non-zero"),
            std::string::npos)
      << error.dump();

  // The range is a limit of the server's, like the others.
  scene["animation"]["frames"] = {1, 101};
  const HttpResult long_one = submit(scene);
  ASSERT_TRUE(is_error(long_one, 422, "over_limit")) << long_one.body;
  EXPECT_EQ(json::parse(long_one.body)["error"]["limit"], "max_frames");

  // And it keeps serving stills.
  EXPECT_EQ(submit(test::showcase(16, 16, 1, 16)).status, 201);
}

TEST(FarmProtocolTest, EveryErrorHasOneShapeAndTheServerKeepsServing) {
  Farm farm("proto-errors", 0);
  HttpClient http = farm.http(10s);

  // 400
  EXPECT_TRUE(is_error(http.request("POST", "/v1/jobs", "{\"scene\": "), 400, "malformed_json"));
  EXPECT_TRUE(is_error(
      http.request("POST", "/v1/jobs", json{{"priority", 101}, {"scene", one_tile_scene()}}.dump()),
      400, "invalid_request"));
  EXPECT_TRUE(
      is_error(http.request("POST", "/v1/workers", "{\"threads\": 2}"), 400, "invalid_request"));
  RawWorker worker(farm.url(), "errors");
  EXPECT_TRUE(is_error(worker.send("POST", "/v1/workers/" + worker.id() + "/claim?wait_s=soon"),
                       400, "invalid_request"));
  EXPECT_TRUE(is_error(http.request("GET", "/v1/jobs?state=sleeping"), 400, "invalid_request"));

  // 404
  EXPECT_TRUE(is_error(http.request("GET", "/v1/nothing"), 404, "not_found"));
  EXPECT_TRUE(is_error(http.request("GET", "/v1/jobs/j-missing"), 404, "not_found"));
  EXPECT_TRUE(is_error(http.request("DELETE", "/v1/jobs/j-missing"), 404, "not_found"));
  EXPECT_TRUE(is_error(worker.send("GET", "/v1/scenes/0123abcd"), 404, "not_found"));
  EXPECT_TRUE(is_error(http.request("POST", "/v1/workers/w-missing/claim?wait_s=0"), 404,
                       "unknown_worker"));

  // 405, naming what is allowed
  const HttpResult put_jobs = http.request("PUT", "/v1/jobs", "{}");
  EXPECT_TRUE(is_error(put_jobs, 405, "method_not_allowed"));
  ASSERT_TRUE(put_jobs.headers.contains("allow"));
  EXPECT_NE(put_jobs.headers.at("allow").find("GET"), std::string::npos)
      << put_jobs.headers.at("allow");
  EXPECT_NE(put_jobs.headers.at("allow").find("POST"), std::string::npos)
      << put_jobs.headers.at("allow");
  const HttpResult delete_health = http.request("DELETE", "/healthz");
  EXPECT_TRUE(is_error(delete_health, 405, "method_not_allowed"));
  EXPECT_EQ(delete_health.headers.contains("allow") ? delete_health.headers.at("allow") : "",
            "GET, HEAD");
  // HEAD on every GET route, as load balancers probe: the GET's header, no body.
  const HttpResult head_health = http.request("HEAD", "/healthz");
  EXPECT_EQ(head_health.status, 200);
  EXPECT_TRUE(head_health.body.empty()) << head_health.body;

  // 409: the state is wrong for the request
  const std::string job_id = farm.api().submit("queued", 50, one_tile_scene())["id"];
  EXPECT_TRUE(
      is_error(http.request("GET", "/v1/jobs/" + job_id + "/image?format=png"), 409, "not_ready"));
  EXPECT_TRUE(is_error(http.request("DELETE", "/v1/jobs/" + job_id), 409, "not_finished"));
  ASSERT_EQ(http.request("POST", "/v1/jobs/" + job_id + "/cancel").status, 200);
  EXPECT_TRUE(
      is_error(http.request("POST", "/v1/jobs/" + job_id + "/cancel"), 409, "already_finished"));

  // 410: no such lease (any more)
  EXPECT_TRUE(is_error(worker.send("POST", "/v1/leases/l-missing/heartbeat"), 410, "lease_lost"));

  // 413, answered from the headers: the bodies announced here are never sent.
  for (const auto& [head, what] : {
           std::pair{
               "POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
               "Content-Length: 1073741824\r\n\r\n",
               "a 1 GiB job over the 64 MiB limit"},
           std::pair{"PUT /v1/leases/l-x/result HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                     "Content-Type: application/octet-stream\r\nContent-Length: 1073741824\r\n\r\n",
                     "a 1 GiB tile over the largest tile's size"},
       }) {
    SCOPED_TRACE(what);
    const RawAnswer answer = send_head_only(farm.port(), head);
    ASSERT_EQ(answer.status, 413) << answer.body;
    HttpResult as_result{answer.status, answer.headers, answer.body};
    EXPECT_TRUE(is_error(as_result, 413, "body_too_large"));
  }
  // Just over the job limit is refused too; the limit is 64 MiB, not some round number above it.
  EXPECT_EQ(send_head_only(
                farm.port(),
                "POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
                "Content-Length: " +
                    std::to_string((64 << 20) + 1) + "\r\n\r\n")
                .status,
            413);

  // After all of that the server is healthy and still takes work.
  HttpClient fresh = farm.http(10s);
  const HttpResult health = fresh.request("GET", "/healthz");
  EXPECT_EQ(health.status, 200);
  EXPECT_EQ(json::parse(health.body)["status"], "ok");
  EXPECT_EQ(farm.api().submit("after", 50, one_tile_scene())["state"], "queued");
  EXPECT_EQ(farm.api().jobs("", 10)["jobs"].size(), 2u);
}

TEST(FarmProtocolTest, AWorkerThatLeftRegistersAgainBeforeItClaims) {
  Farm farm("proto-left", 0);
  farm.api().submit("one tile", 50, one_tile_scene());
  RawWorker worker(farm.url(), "leaver");
  EXPECT_EQ(worker.leave().status, 204);
  EXPECT_EQ(worker_info(farm, worker.id())["state"], "left");
  const HttpResult claimed = worker.claim(0);
  EXPECT_TRUE(is_error(claimed, 404, "unknown_worker")) << claimed.body;
  EXPECT_NE(claimed.body.find("register again"), std::string::npos) << claimed.body;
  EXPECT_EQ(worker_info(farm, worker.id())["state"], "left") << "a claim brought it back";
  // Registered again, under a new id, it gets the tile.
  RawWorker again(farm.url(), "leaver");
  EXPECT_NE(again.id(), worker.id());
  EXPECT_EQ(again.claim(5).status, 200);
}

// The worker token says only that a caller may be some worker; the secret its registration
// gave says which. Another worker's lease, and another worker's name, are refused with 403,
// and none of the refused calls changes the lease.
TEST(FarmProtocolTest, EveryWorkerCallProvesWhichWorkerItIs) {
  Farm farm("proto-identity", 0);
  const std::string job_id = farm.api().submit("one tile", 50, one_tile_scene())["id"];
  RawWorker holder(farm.url(), "holder");
  RawWorker other(farm.url(), "other");
  EXPECT_EQ(holder.secret().size(), 64u);
  EXPECT_NE(holder.secret(), other.secret());
  const HttpResult claimed = holder.claim(5);
  ASSERT_EQ(claimed.status, 200) << claimed.body;
  const json lease = json::parse(claimed.body);
  const std::string lease_id = lease["id"];
  const std::string scene = "/v1/scenes/" + lease["scene_digest"].get<std::string>();
  const std::string on_lease = "/v1/leases/" + lease_id;

  // Another worker, with the worker token (none is set here) and its own secret.
  for (const auto& [method, target, body, type] : {
           std::tuple{"POST", on_lease + "/heartbeat", std::string(), "application/json"},
           std::tuple{"POST", on_lease + "/extend?max_tiles=1", std::string(), "application/json"},
           std::tuple{"PUT", on_lease + "/result", tile_body(16, 16, 0.5f),
                      "application/octet-stream"},
           std::tuple{"POST", on_lease + "/fail", json{{"tile", 0}, {"error", "no"}}.dump(),
                      "application/json"},
           std::tuple{"POST", on_lease + "/release", std::string(), "application/json"},
           std::tuple{"POST", "/v1/workers/" + holder.id() + "/claim?wait_s=0", std::string(),
                      "application/json"},
           std::tuple{"DELETE", "/v1/workers/" + holder.id(), std::string(), "application/json"},
       }) {
    SCOPED_TRACE(std::string(method) + " " + target);
    const HttpResult refused = other.send(method, target, body, type, {{"X-Tessera-Rays", "1"}});
    EXPECT_TRUE(is_error(refused, 403, "wrong_worker")) << refused.body;
    // With no secret at all, the same call is refused as unauthenticated.
    HttpClient bare = farm.http(10s);
    const HttpResult anonymous =
        bare.request(method, target, body, type, {{"X-Tessera-Rays", "1"}});
    EXPECT_TRUE(is_error(anonymous, 401, "missing_worker_secret")) << anonymous.body;
  }
  // A made-up secret fetches no scene; a registered worker's does.
  HttpClient bare = farm.http(10s);
  EXPECT_TRUE(is_error(bare.request("GET", scene, {}, "application/json",
                                    {{"X-Tessera-Worker-Secret", std::string(64, 'a')}}),
                       403, "wrong_worker"));
  EXPECT_EQ(other.send("GET", scene).status, 200);

  // Nothing of that touched the lease: its holder still owes the tile and delivers it.
  EXPECT_EQ(worker_info(farm, holder.id())["state"], "rendering");
  const HttpResult beat = holder.heartbeat(lease_id);
  ASSERT_EQ(beat.status, 200) << beat.body;
  EXPECT_EQ(json::parse(beat.body)["tiles"], lease["tiles"]);
  const HttpResult delivered = holder.upload(lease_id, tile_body(16, 16, 0.5f));
  EXPECT_EQ(delivered.status, 200) << delivered.body;
  EXPECT_TRUE(
      test::eventually([&] { return farm.api().job(job_id)["state"] == "completed"; }, 20s));

  // The secret is given once: the workers list never shows it.
  const HttpResult list = farm.http(10s).request("GET", "/v1/workers");
  EXPECT_EQ(list.body.find(holder.secret()), std::string::npos) << list.body;
  EXPECT_EQ(list.body.find("secret"), std::string::npos) << list.body;
  // A worker that left proves nothing any more.
  EXPECT_EQ(other.leave().status, 204);
  EXPECT_TRUE(is_error(other.send("GET", scene), 403, "wrong_worker"));
}

TEST(FarmProtocolTest, AWorkerGoneLongerThanForgetWorkersAfterLeavesTheList) {
  Farm farm("proto-forget", 0, {"--forget-workers-after", "1"});
  RawWorker leaver(farm.url(), "leaver");
  RawWorker stayer(farm.url(), "stayer");
  EXPECT_EQ(leaver.leave().status, 204);
  EXPECT_TRUE(test::eventually([&] { return worker_info(farm, leaver.id()).is_null(); }, 20s))
      << "a worker that left a second ago is still listed";
  EXPECT_FALSE(worker_info(farm, stayer.id()).is_null()) << "a worker that never left was dropped";
}

TEST(FarmProtocolTest, RegistrationStatesTheLimitsAndRefusesAWorkerOfAnotherProtocol) {
  Farm farm("proto-version", 0, {"--max-tile-size", "4096"});
  HttpClient http = farm.http(10s);
  RawWorker worker(farm.url(), "current");
  const json& reply = worker.registration();
  EXPECT_EQ(reply["protocol"], kWorkerProtocolVersion);
  const ProtocolLimits limits = protocol::Registration::read(protocol::FieldReader(reply)).limits;
  EXPECT_EQ(limits.max_result_tiles, 256);
  EXPECT_EQ(limits.max_batch_tiles, 256);
  EXPECT_EQ(limits.max_lease_tiles, 1024);
  // Room for the largest tile this coordinator takes: 4096 x 4096 float32 RGB.
  EXPECT_EQ(limits.max_result_bytes, std::size_t{4096} * 4096 * 12);

  // Builds before protocol 2 state no version; a later one states another.
  for (const json& body :
       {json{{"name", "old"}}, json{{"name", "new"}, {"protocol", kWorkerProtocolVersion + 1}},
        json{{"name", "odd"}, {"protocol", "2"}}}) {
    const HttpResult refused = http.request("POST", "/v1/workers", body.dump());
    EXPECT_TRUE(is_error(refused, 409, "protocol_mismatch")) << body.dump();
    const std::string message = json::parse(refused.body)["error"]["message"];
    EXPECT_NE(message.find("speaks worker protocol " + std::to_string(kWorkerProtocolVersion)),
              std::string::npos)
        << message;
    EXPECT_EQ(json::parse(refused.body)["error"]["path"], "/protocol");
  }
  const json workers = farm.api().workers();
  EXPECT_EQ(workers["workers"].size(), 1u);  // none of them joined
}

TEST(FarmProtocolTest, AResultOverTheTileLimitNamesTheLimitAndTheCountAndShowsOnTheJob) {
  Farm farm("proto-over", 0);
  HttpClient http = farm.http(10s);
  RawWorker worker(farm.url(), "over");
  // 64 tiles of 8 px.
  const std::string job_id = farm.api().submit("over", 50, test::showcase(64, 64, 1, 8))["id"];
  const HttpResult claimed = worker.claim(5, "&max_tiles=4");
  ASSERT_EQ(claimed.status, 200) << claimed.body;
  const json lease = json::parse(claimed.body);
  const std::string lease_id = lease["id"];

  std::string tiles = "0";
  std::string rays = "1";
  for (int i = 1; i < 1365; ++i) {
    tiles += "," + std::to_string(i);
    rays += ",1";
  }
  const HttpResult over = worker.upload_tiles(lease_id, tiles, "", rays);
  ASSERT_TRUE(is_error(over, 413, "too_many_tiles"));
  EXPECT_EQ(json::parse(over.body)["error"]["message"],
            "a result carries at most 256 tiles; this one has 1,365");

  // Seen on the job, which goes on, and the coordinator keeps serving.
  json job = farm.api().job(job_id);
  EXPECT_EQ(job["state"], "running");
  EXPECT_EQ(job["health"]["refused_results"], 1) << job.dump();
  EXPECT_NE(job["health"]["last_problem"].get<std::string>().find("this one has 1,365"),
            std::string::npos)
      << job.dump();
  // And in `tessera status`, for people.
  const test::CliRun status = test::run_cli(farm.dir(), {"--server", farm.url(), "status", job_id});
  EXPECT_EQ(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("trouble: 1 result refused"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find(
                "last problem: a result was refused: 413: a result carries at most 256 tiles"),
            std::string::npos)
      << status.output;
  const int first = lease["tiles"][0]["index"];
  const HttpResult good =
      worker.upload_tiles(lease_id, std::to_string(first), tile_body(8, 8, 1.0f), "5");
  EXPECT_EQ(good.status, 200) << good.body;
  EXPECT_EQ(farm.api().job(job_id)["tiles"]["done"], 1);

  // One byte over the bytes it stated: refused from the headers, naming the limit and the size.
  const std::uint64_t max_bytes = worker.registration()["limits"]["max_result_bytes"];
  const RawAnswer too_big = send_head_only(
      farm.port(), "PUT /v1/leases/" + lease_id +
                       "/result HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                       "Content-Type: application/octet-stream\r\nX-Tessera-Tiles: 0\r\n"
                       "Content-Length: " +
                       std::to_string(max_bytes + 1) + "\r\n\r\n");
  ASSERT_EQ(too_big.status, 413) << too_big.body;
  EXPECT_NE(too_big.body.find("the request body of " + with_thousands(max_bytes + 1) +
                              " bytes exceeds this route's limit of " + with_thousands(max_bytes) +
                              " bytes"),
            std::string::npos)
      << too_big.body;
}

}  // namespace
}  // namespace tessera
