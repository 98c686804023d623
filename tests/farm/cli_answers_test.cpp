// The real `tessera` program against servers that do not answer as a coordinator does: a
// proxy's error page, an empty or HTML 200, JSON of the wrong shape, a connection closed
// without an answer. Whatever comes back, the CLI prints one line starting "error:" and
// exits with its documented code (3: unreachable or a bad gateway; 1: any other failed
// request); it never aborts.
#include <utility>  // before Asio: Boost 1.74 with GCC 12 in C++20 needs it

#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio/io_context.hpp>

#include "common/protocol/jobs.hpp"
#include "server/http/http_server.hpp"
#include "server/http/router.hpp"
#include "tests/farm/process.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Answers every route the CLI calls with one canned answer.
class Stranger {
 public:
  explicit Stranger(HttpResponse answer) {
    const Handler reply = [answer](HttpRequest&&, Respond respond) { respond(answer); };
    for (const auto& [method, pattern] :
         std::vector<std::pair<std::string, std::string>>{{"GET", "/v1/jobs"},
                                                          {"POST", "/v1/jobs"},
                                                          {"GET", "/v1/jobs/{id}"},
                                                          {"DELETE", "/v1/jobs/{id}"},
                                                          {"POST", "/v1/jobs/{id}/cancel"},
                                                          {"GET", "/v1/jobs/{id}/image"},
                                                          {"GET", "/v1/workers"}})
      router_.add(method, pattern, reply, RouteOptions{}.with_content_type(""));
    HttpServerOptions options;
    options.address = "127.0.0.1";
    options.port = 0;
    server_ = std::make_unique<HttpServer>(io_, router_, options);
    thread_ = std::thread([this] { io_.run(); });
  }
  ~Stranger() {
    server_->stop();
    thread_.join();
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(server_->port()); }

 private:
  boost::asio::io_context io_;
  Router router_;
  std::unique_ptr<HttpServer> server_;
  std::thread thread_;
};

fs::path fresh_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("tessera-cli-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct CliRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

CliRun run_cli(const fs::path& dir, const std::vector<std::string>& args) {
  static int counter = 0;
  const fs::path log = dir / ("cli-" + std::to_string(++counter) + ".log");
  std::optional<int> status;
  {
    test::Process cli(TESSERA_CLI_BIN, args, log);
    status = cli.wait_for(30s);
  }
  CliRun run;
  std::ifstream in(log);
  std::ostringstream text;
  text << in.rdbuf();
  run.output = text.str();
  if (status && WIFEXITED(*status)) run.exit_code = WEXITSTATUS(*status);
  return run;
}

// The commands that talk to a server, each with what it needs.
std::vector<std::vector<std::string>> server_commands(const fs::path& dir) {
  const std::string scene = std::string(TESSERA_SOURCE_DIR) + "/tests/data/tiny.json";
  // A whole id: a shorter one would be looked up first (GET /v1/jobs?id_prefix=).
  const std::string job = "j-" + std::string(32, '1');
  return {{"status", job},
          {"list"},
          {"workers"},
          {"watch", job},
          {"cancel", job},
          {"rm", job},
          {"get", job, "-o", (dir / "out.png").string()},
          {"submit", scene}};
}

// One line of the output starts with "error: ", and it is the only line.
void expect_one_error_line(const CliRun& run) {
  EXPECT_EQ(run.output.rfind("error: ", 0), 0u) << run.output;
  EXPECT_EQ(run.output.find('\n'), run.output.size() - 1) << run.output;
  EXPECT_EQ(run.output.find("terminate called"), std::string::npos) << run.output;
}

struct Answer {
  const char* what;
  HttpResponse response;
  int exit_code;
};

TEST(CliAnswersTest, EveryStrangeAnswerIsOneLineAndItsExitCode) {
  const fs::path dir = fresh_dir("cli-answers");
  const std::string page =
      "<html>\n<head><title>502 Bad Gateway</title></head>\n"
      "<body><center>nginx</center></body>\n</html>\n";
  const std::vector<Answer> answers = {
      {"an empty 200", {200, "application/json", "", {}}, 1},
      {"an HTML 200", {200, "text/html", "<html>\n<body>Welcome</body>\n</html>\n", {}}, 1},
      {"JSON of the wrong types",
       {200, "application/json", R"({"id": 5, "state": [], "jobs": "x", "workers": 7})", {}},
       1},
      {"a JSON array", {200, "application/json", "[1, 2, 3]", {}}, 1},
      {"a redirect", {302, "text/html", "<a href=\"https://elsewhere/\">moved</a>", {}}, 1},
      {"a proxy's 502 page", {502, "text/html", page, {}}, 3},
      {"a proxy's 503", {503, "text/html", "<html>\nService Unavailable\n</html>", {}}, 3},
      {"a bare 504", {504, "", "", {}}, 3},
      {"a 404 in plain text", {404, "text/plain", "not found\n", {}}, 1},
      {"a coordinator's error",
       {500, "application/json", R"({"error": {"code": "internal_error", "message": "boom"}})", {}},
       1},
  };
  for (const Answer& answer : answers) {
    Stranger server(answer.response);
    for (const auto& command : server_commands(dir)) {
      SCOPED_TRACE(std::string(answer.what) + ": tessera " + command.front());
      std::vector<std::string> args = {"--server", server.url()};
      args.insert(args.end(), command.begin(), command.end());
      const CliRun run = run_cli(dir, args);
      // `rm` asks nothing of a 2xx answer's body: any one is a success.
      if (command.front() == "rm" && answer.response.status < 300) {
        EXPECT_EQ(run.exit_code, 0) << run.output;
        continue;
      }
      EXPECT_EQ(run.exit_code, answer.exit_code) << run.output;
      expect_one_error_line(run);
      EXPECT_FALSE(fs::exists(dir / "out.png.part")) << "a half-written download was left";
      EXPECT_FALSE(fs::exists(dir / "out.png")) << "a page was saved as the image";
    }
  }
}

TEST(CliAnswersTest, NoAnswerAtAllIsUnreachable) {
  const fs::path dir = fresh_dir("cli-no-answer");
  // Accepts and closes at once: no HTTP answer comes.
  const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(::listen(listener, 16), 0);
  socklen_t size = sizeof address;
  ::getsockname(listener, reinterpret_cast<sockaddr*>(&address), &size);
  std::atomic<bool> done{false};
  std::thread closer([&] {
    while (!done) {
      const int fd = ::accept(listener, nullptr, nullptr);
      if (fd >= 0) ::close(fd);
    }
  });
  const std::string url = "http://127.0.0.1:" + std::to_string(ntohs(address.sin_port));
  const CliRun run = run_cli(dir, {"--server", url, "list"});
  EXPECT_EQ(run.exit_code, 3) << run.output;
  expect_one_error_line(run);
  done = true;
  ::shutdown(listener, SHUT_RDWR);
  ::close(listener);
  closer.join();
}

TEST(CliAnswersTest, AnyServerUrlIsOneLine) {
  const fs::path dir = fresh_dir("cli-urls");
  const std::vector<std::pair<std::string, int>> urls = {
      {"https://127.0.0.1:1", 3},  // nothing listens there (TLS itself: farm_tls_test.cpp)
      {"ftp://127.0.0.1", 2},     {"http://", 2},
      {"http://[::1", 2},         {"http://127.0.0.1:99999", 2},
      {"http://u@127.0.0.1", 2},  {"http://127.0.0.1/v1", 2},
      {"127.0.0.1:1", 3},  // a bare host:port is http://, and nothing listens there
  };
  for (const auto& [url, code] : urls) {
    SCOPED_TRACE(url);
    const CliRun run = run_cli(dir, {"--server", url, "list"});
    EXPECT_EQ(run.exit_code, code) << run.output;
    expect_one_error_line(run);
  }
}

// A coordinator busy reading other large submissions answers 503 busy with Retry-After and
// keeps nothing: `tessera submit` sends the job again after that wait, and it is created.
TEST(CliAnswersTest, ASubmissionAnsweredBusyGoesAgainAfterRetryAfter) {
  const fs::path dir = fresh_dir("cli-busy");
  boost::asio::io_context io;
  Router router;
  std::atomic<int> posts{0};
  router.add(
      "POST", "/v1/jobs",
      [&posts](HttpRequest&&, Respond respond) {
        if (++posts <= 2) {
          HttpResponse busy{503,
                            "application/json",
                            R"({"error": {"code": "busy", "message": "busy reading others"}})",
                            {{"Retry-After", "1"}}};
          return respond(std::move(busy));
        }
        protocol::JobStatus job;
        job.id = "j-busy-then-taken";
        job.name = "tiny";
        job.width = job.height = 8;
        job.created_at = "2026-12-05T00:00:00.000Z";
        respond(HttpResponse{201, "application/json", protocol::to_json(job).dump(), {}});
      },
      RouteOptions{}.with_content_type(""));
  HttpServerOptions options;
  options.address = "127.0.0.1";
  options.port = 0;
  HttpServer server(io, router, options);
  std::thread thread([&io] { io.run(); });
  const CliRun run =
      run_cli(dir, {"--server", "http://127.0.0.1:" + std::to_string(server.port()), "--json",
                    "submit", std::string(TESSERA_SOURCE_DIR) + "/tests/data/tiny.json"});
  server.stop();
  thread.join();
  EXPECT_EQ(posts.load(), 3) << run.output;
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("j-busy-then-taken"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace tessera
