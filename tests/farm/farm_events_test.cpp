// Server-sent events on a real coordinator with real workers: a job's tiles arrive as
// events with their pixels (the image's own), the farm's stream tells of jobs and workers,
// a stream resumes after its last event, stays alive when idle, and a client that stops
// reading holds nobody up.
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "tests/farm/farm_fixture.hpp"
#include "tests/unit/server/raw_connection.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;
namespace fs = std::filesystem;

struct Event {
  std::string id;
  std::string type;
  json data;
  bool comment = false;
};

Event parse(const std::string& block) {
  Event event;
  std::istringstream lines(block);
  for (std::string line; std::getline(lines, line);) {
    if (line.starts_with(":")) event.comment = true;
    if (line.starts_with("id: ")) event.id = line.substr(4);
    if (line.starts_with("event: ")) event.type = line.substr(7);
    if (line.starts_with("data: ")) event.data = json::parse(line.substr(6));
  }
  return event;
}

// A stream opened on `target`, its header read.
struct Stream {
  Stream(const Farm& farm, const std::string& target, const std::string& last_event_id = "",
         int receive_buffer = 0)
      : connection(static_cast<std::uint16_t>(farm.port()), receive_buffer) {
    connection.send("GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" +
                    (last_event_id.empty() ? "" : "Last-Event-ID: " + last_event_id + "\r\n") +
                    "\r\n");
    header = connection.read_header();
  }
  // The next event that is not a comment; an empty type at the deadline.
  Event next(std::chrono::milliseconds limit = 30s) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline) {
      const std::string block =
          connection.read_event(std::chrono::duration_cast<std::chrono::milliseconds>(
              deadline - std::chrono::steady_clock::now()));
      if (block.empty()) break;
      Event event = parse(block);
      if (!event.comment) return event;
    }
    return {};
  }
  raw_http::RawConnection connection;
  std::string header;
};

std::vector<std::uint8_t> decoded(const std::string& base64) {
  static const std::string digits =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<std::uint8_t> out;
  std::uint32_t bits = 0;
  int count = 0;
  for (const char c : base64) {
    if (c == '=') break;
    bits = (bits << 6) | static_cast<std::uint32_t>(digits.find(c));
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<std::uint8_t>((bits >> count) & 0xff));
    }
  }
  return out;
}

TEST(FarmEventsTest, AJobsTilesArriveAsEventsWithThePixelsOfItsImage) {
  Farm farm("events-tiles", 0);
  const json scene = test::showcase(64, 32, 1, 16);  // 8 tiles
  const std::string id = farm.api().submit("watched", 50, scene)["id"];
  Stream stream(farm, "/v1/jobs/" + id + "/events");
  ASSERT_TRUE(test::contains(stream.header, "200 OK")) << stream.header;
  ASSERT_TRUE(test::contains(stream.header, "Content-Type: text/event-stream")) << stream.header;
  auto worker = farm.start_worker("painter", 1);
  std::map<int, json> done;
  std::set<int> rendering;
  std::string last_state;
  while (done.size() < 8 || last_state != "completed") {
    const Event event = stream.next();
    ASSERT_FALSE(event.type.empty()) << "the stream went quiet with " << done.size() << " tiles";
    if (event.type == "tile" && event.data["state"] == "rendering") {
      EXPECT_EQ(event.data["worker_name"], "painter");
      rendering.insert(event.data["index"].get<int>());
    }
    if (event.type == "tile" && event.data["state"] == "done")
      done[event.data["index"].get<int>()] = event.data;
    if (event.type == "job") last_state = event.data["state"];
  }
  EXPECT_EQ(rendering.size(), 8u) << "each tile is seen going out";
  // Each tile's bytes are its part of the image, coded as the job's PNG is.
  const Image image = test::farm_image(farm, id);
  for (const auto& [index, tile] : done) {
    const int x0 = tile["x"], y0 = tile["y"], width = tile["width"], height = tile["height"];
    EXPECT_GT(tile["render_ms"].get<double>(), 0);
    const std::vector<std::uint8_t> bytes = decoded(tile["pixels"]);
    ASSERT_EQ(bytes.size(), static_cast<std::size_t>(width * height * 3));
    std::size_t differ = 0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) {
          const float linear = image.pixels()[((y0 + y) * image.width() + x0 + x) * 3 + c];
          differ += bytes[(y * width + x) * 3 + c] != code8(linear, OutputTransfer::srgb);
        }
    EXPECT_EQ(differ, 0u) << "tile " << index;
  }
}

TEST(FarmEventsTest, TheFarmsStreamTellsOfJobsAndWorkersAndResumesAfterItsLastEvent) {
  Farm farm("events-farm", 0);
  std::string resume_after;
  std::unique_ptr<test::Process> worker;
  {
    Stream stream(farm, "/v1/events");
    worker = farm.start_worker("joiner", 1);
    Event joined = stream.next();
    ASSERT_EQ(joined.type, "worker");
    EXPECT_EQ(joined.data["change"], "joined");
    EXPECT_EQ(joined.data["worker"]["name"], "joiner");
    resume_after = joined.id;
  }  // the client goes
  const std::string id = farm.api().submit("followed", 60, test::showcase(32, 32, 1, 16))["id"];
  ASSERT_EQ(farm.wait_finished(id)["state"], "completed");
  // Resumed: what came since, from the job's submission to its completion, in order.
  Stream resumed(farm, "/v1/events", resume_after);
  std::vector<std::string> states;
  while (states.empty() || states.back() != "completed") {
    const Event event = resumed.next(20s);
    ASSERT_FALSE(event.type.empty()) << "seen: " << states.size();
    ASSERT_NE(event.type, "resync");
    if (event.type == "job" && event.data["id"] == id) states.push_back(event.data["state"]);
  }
  EXPECT_EQ(states.front(), "queued");
  // An id of another coordinator process (one since restarted): start again from state.
  Stream stranger(farm, "/v1/events", "0000-17");
  EXPECT_EQ(stranger.next(10s).type, "resync");
}

TEST(FarmEventsTest, AnIdleStreamGetsKeepAlives) {
  Farm farm("events-idle", 0, {"--event-keepalive", "0.2"});
  Stream stream(farm, "/v1/events");
  EXPECT_EQ(stream.connection.read_event(10s), ": open\n\n") << "at once";
  EXPECT_EQ(stream.connection.read_event(10s), ": keepalive\n\n");
  EXPECT_EQ(stream.connection.read_event(10s), ": keepalive\n\n");
}

TEST(FarmEventsTest, AClientThatStopsReadingHoldsNobodyUpAndIsToldToResync) {
  // A queue that a reader on a busy machine does not fill, and a job of far more events:
  // 4,096 tiles of about 1 KB of pixels each, twice the queue and the stream's socket
  // buffers (256 KiB) together.
  Farm farm("events-stalled", 0, {"--event-queue", "2000"});
  const json scene = test::showcase(2048, 512, 1, 16);
  const std::string id = farm.api().submit("busy", 50, scene)["id"];
  // One client never reads (and its socket takes little), one reads all the while.
  Stream stalled(farm, "/v1/jobs/" + id + "/events", "", 2048);
  Stream reader(farm, "/v1/jobs/" + id + "/events");
  auto worker = farm.start_worker("busy", 2);
  int tiles = 0;
  while (tiles < 4096) {
    const Event event = reader.next();
    ASSERT_FALSE(event.type.empty()) << tiles << " tiles seen";
    ASSERT_NE(event.type, "resync");
    tiles += event.type == "tile" && event.data["state"] == "done";
  }
  ASSERT_EQ(farm.wait_finished(id)["state"], "completed");
  // The stalled one, reading at last, is told it missed events instead of being sent them.
  bool resync = false;
  int read = 0;
  while (!resync) {
    const Event event = stalled.next(10s);
    if (event.type.empty()) break;
    resync = event.type == "resync";
    ++read;
  }
  EXPECT_TRUE(resync) << read << " events read, none of them resync";
}

// The requests of one route and status the coordinator answered, from its metrics.
double answered(Farm& farm, const std::string& route, const std::string& status) {
  const HttpResult metrics = farm.http(10s).request("GET", "/metrics", "", "");
  const std::string series = "tessera_http_requests_total{route=\"" + route +
                             "\",method=\"GET\",status=\"" + status + "\"} ";
  const std::size_t at = metrics.body.find(series);
  return at == std::string::npos ? 0 : std::stod(metrics.body.substr(at + series.size()));
}

TEST(FarmEventsTest, WatchAndSubmitWaitFollowEventsInsteadOfPolling) {
  Farm farm("events-watch", 1);
  const std::string id = farm.api().submit("watched", 50, test::showcase(192, 192, 2, 16))["id"];
  const test::CliRun watched =
      test::run_cli(farm.dir(), {"--server", farm.url(), "watch", id.substr(0, 10)}, 120s);
  EXPECT_EQ(watched.exit_code, 0) << watched.output;
  EXPECT_TRUE(test::contains(watched.output, "completed 144/144 tiles")) << watched.output;
  // One stream, and the job's status read once when it opened: no poll.
  EXPECT_EQ(answered(farm, "/v1/events", "200"), 1);
  EXPECT_LE(answered(farm, "/v1/jobs/{id}", "200"), 1);
  const fs::path scene_file = farm.dir() / "scene.json";
  test::write_text(scene_file, test::showcase(96, 96, 1, 16).dump());
  const test::CliRun waited = test::run_cli(
      farm.dir(), {"--server", farm.url(), "submit", scene_file.string(), "--wait"}, 120s);
  EXPECT_EQ(waited.exit_code, 0) << waited.output;
  EXPECT_TRUE(test::contains(waited.output, "completed 36/36 tiles")) << waited.output;
  EXPECT_EQ(answered(farm, "/v1/events", "200"), 2);
  EXPECT_LE(answered(farm, "/v1/jobs/{id}", "200"), 2);
}

}  // namespace
}  // namespace tessera
