// A stranger who opens connections by the thousand, idle or as event streams, against a
// coordinator whose descriptors are few (prlimit): the job running meanwhile completes
// with the local render's pixels, /healthz answers throughout, and nothing fails for
// want of a descriptor. The flood comes from 127.0.0.2 and 127.0.0.3, the farm's own
// clients from 127.0.0.1: one stranger's address is capped, the others' are not.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

// Connections from `source` to the coordinator, kept open and opened again as the server
// closes them, until stopped: `count` idle ones, or event streams that read nothing.
class Flood {
 public:
  Flood(std::string source, int port, int count, bool streams)
      : source_(std::move(source)), port_(port), count_(count), streams_(streams) {
    thread_ = std::thread([this] { run(); });
  }
  ~Flood() {
    stop_ = true;
    thread_.join();
    for (const int fd : fds_)
      if (fd >= 0) ::close(fd);
  }
  Flood(const Flood&) = delete;
  Flood& operator=(const Flood&) = delete;

  // Connections opened so far, first ones and again.
  int opened() const { return opened_.load(); }

 private:
  int connect_one() const {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -1;
    sockaddr_in from{};
    from.sin_family = AF_INET;
    ::inet_pton(AF_INET, source_.c_str(), &from.sin_addr);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(port_));
    ::inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
    if (::bind(fd, reinterpret_cast<sockaddr*>(&from), sizeof from) != 0 ||
        ::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
      ::close(fd);
      return -1;
    }
    if (streams_) {
      const std::string request =
          "GET /v1/events HTTP/1.1\r\nHost: 127.0.0.1\r\nAccept: text/event-stream\r\n\r\n";
      if (::send(fd, request.data(), request.size(), MSG_NOSIGNAL) < 0) {
        ::close(fd);
        return -1;
      }
    }
    return fd;
  }

  void run() {
    fds_.assign(count_, -1);
    std::vector<pollfd> polled(count_);
    while (!stop_) {
      for (int i = 0; i < count_ && !stop_; ++i)
        if (fds_[i] < 0 && (fds_[i] = connect_one()) >= 0) ++opened_;
      // A closed connection reads as end of file: it is opened again. What a stream sends
      // is never read, as a stalled subscriber's is not.
      for (int i = 0; i < count_; ++i) polled[i] = {fds_[i], POLLRDHUP | POLLHUP, 0};
      ::poll(polled.data(), polled.size(), 50);
      for (int i = 0; i < count_; ++i)
        if (fds_[i] >= 0 && (polled[i].revents & (POLLRDHUP | POLLHUP | POLLERR))) {
          ::close(fds_[i]);
          fds_[i] = -1;
        }
    }
  }

  std::string source_;
  int port_;
  int count_;
  bool streams_;
  std::vector<int> fds_;
  std::atomic<int> opened_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// What the kernel says of a process's descriptor limit: "Max open files  SOFT  HARD".
std::string open_files_line(pid_t pid) {
  std::ifstream limits("/proc/" + std::to_string(pid) + "/limits");
  for (std::string line; std::getline(limits, line);)
    if (line.rfind("Max open files", 0) == 0) return line;
  return "";
}

// A coordinator run under prlimit's descriptor limits, with one local worker.
std::unique_ptr<test::Process> start_limited(const fs::path& dir, const std::string& nofile) {
  return std::make_unique<test::Process>(
      "/usr/bin/prlimit",
      std::vector<std::string>{"--nofile=" + nofile, TESSERA_SERVER_BIN, "--listen", "127.0.0.1:0",
                               "--data-dir", (dir / "data").string(), "--local-workers", "1",
                               "--worker-threads", "2", "--port-file", (dir / "port").string(),
                               "--log-level", "info"},
      dir / "server.log");
}

int wait_port(const fs::path& dir) { return test::port_from_file(dir, dir / "server.log"); }

bool have_prlimit() { return fs::exists("/usr/bin/prlimit"); }

// The flood needs 1,500 descriptors of this test process.
bool enough_descriptors_here() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return false;
  if (limit.rlim_cur < 2048 && limit.rlim_max >= 2048) {
    limit.rlim_cur = 2048;
    ::setrlimit(RLIMIT_NOFILE, &limit);
    ::getrlimit(RLIMIT_NOFILE, &limit);
  }
  return limit.rlim_cur >= 2048;
}

TEST(FarmConnectionsTest, TheSoftDescriptorLimitIsRaisedToTheHardOne) {
  if (!have_prlimit()) GTEST_SKIP() << "no /usr/bin/prlimit (util-linux) on this machine";
  const fs::path dir = test::fresh_dir("connections-raise");
  auto server = start_limited(dir, "256:1024");
  wait_port(dir);
  // The server is prlimit's child once prlimit has exec'd it: the same pid.
  const std::string line = open_files_line(server->pid());
  EXPECT_NE(line.find("1024                 1024"), std::string::npos) << line;
  const std::string log = test::read_text(dir / "server.log");
  EXPECT_NE(log.find("1024 file descriptors (raised from 256): up to 896 connections, 224 from "
                     "one address"),
            std::string::npos)
      << log;
}

TEST(FarmConnectionsTest, AFloodOfIdleConnectionsAndStreamsFailsNoJobAndHealthzAnswers) {
  if (!have_prlimit()) GTEST_SKIP() << "no /usr/bin/prlimit (util-linux) on this machine";
  if (!enough_descriptors_here())
    GTEST_SKIP() << "this test process cannot have the 2,048 descriptors its flood needs";
  const fs::path dir = test::fresh_dir("connections-flood");
  // 256 descriptors: 192 connections, 48 from one address.
  auto server = start_limited(dir, "256:256");
  const int port = wait_port(dir);
  const std::string url = "http://127.0.0.1:" + std::to_string(port);
  test::JsonApi api(url);
  ASSERT_TRUE(test::eventually([&] { return api.workers()["workers"].size() == 1; }, 20s));

  Flood idle("127.0.0.2", port, 1100, false);
  Flood streams("127.0.0.3", port, 400, true);
  ASSERT_TRUE(
      test::eventually([&] { return idle.opened() >= 1100 && streams.opened() >= 400; }, 30s))
      << idle.opened() << " idle, " << streams.opened() << " streams";

  const json scene = test::showcase(160, 120, 2, 16);  // 80 tiles
  const std::string id = api.submit("under a flood", 50, scene)["id"];
  json job;
  int health_checks = 0;
  ASSERT_TRUE(test::eventually(
      [&] {
        // A fresh connection each time, as a load balancer's health check makes.
        HttpClient health(url, 3s);
        EXPECT_EQ(health.request("GET", "/healthz").status, 200);
        ++health_checks;
        job = api.job(id);
        return job["state"] != "queued" && job["state"] != "running";
      },
      60s))
      << job.dump();
  EXPECT_EQ(job["state"], "completed") << job.dump();
  EXPECT_GT(health_checks, 0);
  const fs::path file = dir / "flooded.exr";
  test::write_text(file, api.image(id, "exr", false));
  EXPECT_TRUE(test::same_pixels(read_image(file), test::render_image(scene, 2)));
  // The stranger was held to his share: far more connections were opened than kept.
  EXPECT_GT(idle.opened(), 1100 + 48);
  const std::string log = test::read_text(dir / "server.log");
  EXPECT_EQ(log.find("Too many open files"), std::string::npos) << log.substr(0, 4000);
}

}  // namespace
}  // namespace tessera
