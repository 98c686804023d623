// Memory is bounded by the request, not amplified by it (issue 24): the coordinator's peak
// RSS, read from /proc, grows by at most 4 times the body for a refused scene and 8 times
// for an accepted one, comes back once the request is done, and submissions over the
// shared budget are refused for now (503, Retry-After) with nothing of them kept.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

// A field of /proc/PID/status in KiB, or -1 where there is no such file.
long status_kib(pid_t pid, const std::string& field) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line))
    if (line.starts_with(field + ":")) return std::stol(line.substr(field.size() + 1));
  return -1;
}

// Resets the process's peak (VmHWM) to its RSS now (Linux 4.0 on); false where it cannot.
bool reset_peak(pid_t pid) {
  std::ofstream clear("/proc/" + std::to_string(pid) + "/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

// A job submission whose scene is the showcase with `spheres` small spheres as objects, in
// the compact JSON a client sends.
std::string submission_with_spheres(std::size_t spheres) {
  json scene = test::showcase(64, 48, 1, 32);
  scene["objects"] = json::array();
  std::string text = json{{"name", "spheres"}, {"scene", scene}}.dump();
  std::string objects;
  objects.reserve(spheres * 70);
  for (std::size_t i = 0; i < spheres; ++i) {
    if (i) objects += ',';
    objects += R"({"type":"sphere","center":[)" + std::to_string(i % 1000) + ".25," +
               std::to_string(i / 1000) + R"(.5,-20],"radius":0.2,"material":"glass"})";
  }
  const std::string empty = R"("objects":[])";
  text.replace(text.find(empty), empty.size(), R"("objects":[)" + objects + "]");
  return text;
}

struct Growth {
  int status = 0;
  std::string body;
  double peak_per_body_byte = 0;
  long before_kib = 0;
};

// Posts `body` and measures the coordinator's peak RSS growth per byte of it.
Growth post_measuring(Farm& farm, const std::string& body) {
  const pid_t pid = farm.server().pid();
  Growth growth;
  growth.before_kib = status_kib(pid, "VmRSS");
  const HttpResult result = farm.http(60s).request("POST", "/v1/jobs", body);
  const long peak_kib = status_kib(pid, "VmHWM");
  growth.status = result.status;
  growth.body = result.body;
  growth.peak_per_body_byte = (peak_kib - growth.before_kib) * 1024.0 / body.size();
  return growth;
}

bool has_proc(Farm& farm) {
  return status_kib(farm.server().pid(), "VmHWM") >= 0 && reset_peak(farm.server().pid());
}

// Within 128 MiB of where it was before the request, once the coordinator has given back
// what the request freed (after its answer, on the store thread).
bool idle_comes_back(Farm& farm, long before_kib) {
  return test::eventually(
      [&] { return status_kib(farm.server().pid(), "VmRSS") <= before_kib + 128 * 1024; }, 10s);
}

TEST(FarmMemoryTest, RefusedSceneCostsNoMoreThanItsBody) {
  Farm farm("mem-refused", 0, {"--max-objects", "1000"});
  if (!has_proc(farm)) GTEST_SKIP() << "no /proc/PID/status and clear_refs to measure with";
  // 250,000 spheres, 17 MB: read whole into nodes, as before issue 24, the peak grew by 16
  // times that.
  const std::string body = submission_with_spheres(250'000);
  const Growth growth = post_measuring(farm, body);
  ASSERT_EQ(growth.status, 422) << growth.body;
  const json error = json::parse(growth.body)["error"];
  EXPECT_EQ(error["limit"], "max_objects");
  EXPECT_EQ(error["path"], "/scene/objects");
  RecordProperty("peak_growth_per_body_byte", std::to_string(growth.peak_per_body_byte));
  EXPECT_LT(growth.peak_per_body_byte, 4.0) << body.size() << " bytes";
  EXPECT_TRUE(idle_comes_back(farm, growth.before_kib));
}

// Refused for its key alone, an unknown member's value is never built.
TEST(FarmMemoryTest, RefusedJunkCostsNoMoreThanItsBody) {
  Farm farm("mem-junk", 0);
  if (!has_proc(farm)) GTEST_SKIP() << "no /proc/PID/status and clear_refs to measure with";
  std::string body = submission_with_spheres(10);
  std::string junk = R"(,"extra":[)";
  for (int i = 0; i < 700'000; ++i) junk += (i ? ",[" : "[") + std::to_string(i) + ",1.5,-2]";
  body.insert(body.rfind("}}"), junk + "]");
  const Growth growth = post_measuring(farm, body);
  ASSERT_EQ(growth.status, 400) << growth.body;
  EXPECT_EQ(json::parse(growth.body)["error"]["path"], "/scene/extra");
  RecordProperty("peak_growth_per_body_byte", std::to_string(growth.peak_per_body_byte));
  EXPECT_LT(growth.peak_per_body_byte, 4.0) << body.size() << " bytes";
}

// A huge value where three numbers belong, in an object or in the camera, is refused
// before its piece is built.
TEST(FarmMemoryTest, RefusedHugeValuesCostNoMoreThanTheirBody) {
  Farm farm("mem-huge-value", 0);
  if (!has_proc(farm)) GTEST_SKIP() << "no /proc/PID/status and clear_refs to measure with";
  std::string huge = "[";
  for (int i = 0; i < 700'000; ++i) huge += (i ? ",[" : "[") + std::to_string(i) + ",1.5,-2]";
  huge += "]";
  for (const auto& [member, path] : std::vector<std::pair<std::string, std::string>>{
           {R"("center":[0.25,0.5,-20])", "/scene/objects/0"}, {R"("eye":)", "/scene/camera"}}) {
    SCOPED_TRACE(path);
    std::string body = submission_with_spheres(10);
    const std::size_t at = body.find(member);
    ASSERT_NE(at, std::string::npos) << member;
    if (member.starts_with(R"("center")"))
      body.replace(at, member.size(), R"("center":)" + huge);
    else
      body.insert(at + member.size(), huge + ",\"unused\":");
    ASSERT_TRUE(reset_peak(farm.server().pid()));
    const Growth growth = post_measuring(farm, body);
    ASSERT_EQ(growth.status, 400) << growth.body.substr(0, 300);
    EXPECT_EQ(json::parse(growth.body)["error"]["path"], path);
    RecordProperty("peak_growth_per_body_byte", std::to_string(growth.peak_per_body_byte));
    EXPECT_LT(growth.peak_per_body_byte, 4.0) << body.size() << " bytes";
  }
}

TEST(FarmMemoryTest, AcceptedSceneCostsAFewTimesItsBody) {
  Farm farm("mem-accepted", 0);
  if (!has_proc(farm)) GTEST_SKIP() << "no /proc/PID/status and clear_refs to measure with";
  const std::string body = submission_with_spheres(100'000);  // the default max_objects
  const Growth growth = post_measuring(farm, body);
  ASSERT_EQ(growth.status, 201) << growth.body;
  RecordProperty("peak_growth_per_body_byte", std::to_string(growth.peak_per_body_byte));
  EXPECT_LT(growth.peak_per_body_byte, 8.0) << body.size() << " bytes";
  EXPECT_TRUE(idle_comes_back(farm, growth.before_kib));
}

// Submissions sent together while the budget takes one at a time: some are told to come
// back later, and every one that does is created, once.
TEST(FarmMemoryTest, SubmissionsOverTheBudgetAreToldToRetry) {
  const std::string body = submission_with_spheres(40'000);
  // Each is reckoned as 4 times its body: one fits, two do not.
  Farm farm("mem-busy", 0, {"--submit-memory-budget", std::to_string(6 * body.size())});
  constexpr int kAtOnce = 6;
  int created = 0;
  int busy = 0;
  for (int round = 0; round < 10 && busy == 0; ++round) {
    std::vector<HttpResult> results(kAtOnce);
    std::vector<std::thread> threads;
    for (int i = 0; i < kAtOnce; ++i)
      threads.emplace_back(
          [&, i] { results[i] = farm.http(60s).request("POST", "/v1/jobs", body); });
    for (auto& thread : threads) thread.join();
    for (const HttpResult& result : results) {
      if (result.status == 201) {
        ++created;
        continue;
      }
      ASSERT_EQ(result.status, 503) << result.body;
      ++busy;
      EXPECT_EQ(json::parse(result.body)["error"]["code"], "busy");
      ASSERT_TRUE(result.headers.contains("retry-after"));
      EXPECT_GE(std::stoi(result.headers.at("retry-after")), 1);
    }
  }
  ASSERT_GT(busy, 0) << "no submission was ever refused";
  // Sent again, one at a time, each is created.
  for (int i = 0; i < busy; ++i) {
    const HttpResult again = farm.http(60s).request("POST", "/v1/jobs", body);
    EXPECT_EQ(again.status, 201) << again.body;
    ++created;
  }
  // Nothing of a refused one was kept: the jobs are exactly those answered 201.
  EXPECT_EQ(farm.api().jobs("", 1000)["jobs"].size(), static_cast<std::size_t>(created));
}

}  // namespace
}  // namespace tessera

namespace tessera {
namespace {

// A flood of event streams that read nothing, each queueing a job's tiles with their
// pixels, then closed: the memory they took goes back to the system (glibc keeps it in its
// arenas unless asked: 128 MiB before, 540 with 2,000 streams open, 491 after they closed).
TEST(FarmMemoryTest, MemoryGoesBackAfterAFloodOfEventStreams) {
  Farm farm("memory-streams", 1, {"--worker-threads", "2"});
  if (!has_proc(farm)) GTEST_SKIP() << "no /proc/PID/status to measure with";
  const pid_t pid = farm.server().pid();
  const long before = status_kib(pid, "VmRSS");
  const std::string id = farm.api().submit("watched", 50, test::showcase(640, 480, 1, 8))["id"];
  std::vector<int> streams;
  for (int i = 0; i < 1000; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    ASSERT_GE(fd, 0) << "cannot open a socket: " << std::strerror(errno);
    // A small receive window, so that the coordinator queues what the reader does not take.
    const int window = 4096;
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &window, sizeof window);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(farm.port()));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to), 0);
    const std::string request = "GET /v1/jobs/" + id +
                                "/events HTTP/1.1\r\nHost: 127.0.0.1\r\nAccept: "
                                "text/event-stream\r\n\r\n";
    ASSERT_GT(::send(fd, request.data(), request.size(), MSG_NOSIGNAL), 0);
    streams.push_back(fd);
  }
  ASSERT_EQ(farm.wait_finished(id, 120s)["state"], "completed");
  const long open = status_kib(pid, "VmRSS");
  ASSERT_GT(open - before, 64 * 1024) << "the streams took too little to tell: make more";
  for (const int fd : streams) ::close(fd);
  // Back to within a third of what they took, once the coordinator sees them gone.
  EXPECT_TRUE(test::eventually(
      [&] { return status_kib(pid, "VmRSS") - before < (open - before) / 3; }, 15s))
      << "RSS " << before << " KiB before, " << open << " with the streams open, "
      << status_kib(pid, "VmRSS") << " after they closed";
}

}  // namespace
}  // namespace tessera
