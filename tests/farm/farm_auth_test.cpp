// Strangers: with tokens set, every route of docs/openapi.yaml but /healthz refuses a
// request without the token of its role, before reading any body; local workers get
// their token without it showing in a process list; and a coordinator will not listen
// beyond loopback without tokens unless told --insecure.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "common/protocol/limits.hpp"
#include "tests/farm/farm_fixture.hpp"
#include "tests/unit/server/openapi_routes.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using test::Farm;

const std::string api_token = "api-token-" + std::to_string(::getpid());
const std::string worker_token = "worker-token-" + std::to_string(::getpid());

// A farm whose tokens come from files, as a careful operator would give them.
std::vector<std::string> token_args(const fs::path& dir) {
  fs::create_directories(dir);
  test::write_text(dir / "api.token", api_token + "\n");
  test::write_text(dir / "worker.token", worker_token + "\n");
  // The API token's file private, as the README's recipe makes it; the worker token's left
  // as a careless user leaves it (0644), which the coordinator warns of.
  fs::permissions(dir / "api.token", fs::perms::owner_read | fs::perms::owner_write);
  fs::permissions(dir / "worker.token", fs::perms::owner_read | fs::perms::owner_write |
                                            fs::perms::group_read | fs::perms::others_read);
  return {"--api-token-file", (dir / "api.token").string(), "--worker-token-file",
          (dir / "worker.token").string()};
}

// "/v1/jobs/{id}/image" -> "/v1/jobs/x/image"
std::string concrete(const std::string& pattern) {
  // A dashboard file by a name the coordinator has: /ui/{name} answers 404 for any other.
  const std::string named =
      std::regex_replace(pattern, std::regex(R"(^/ui/\{name\}$)"), "/ui/app.js");
  return std::regex_replace(named, std::regex(R"(\{[a-z_]+\})"), "x");
}

// The status of a request announcing a 1 GiB body that is never sent: only an answer from
// the headers alone arrives before the 10 s receive timeout.
int status_for_header_only(int port, const std::string& head) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  const timeval timeout{10, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  int status = 0;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0 &&
      ::send(fd, head.data(), head.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(head.size())) {
    char buffer[256] = {};
    if (::recv(fd, buffer, sizeof buffer - 1, 0) > 12 &&
        std::string(buffer).rfind("HTTP/1.1 ", 0) == 0)
      status = std::stoi(std::string(buffer + 9, 3));
  }
  ::close(fd);
  return status;
}

TEST(FarmAuthTest, EveryRouteRefusesStrangersAndTheOtherRole) {
  const fs::path secrets = test::fresh_dir("auth-routes-secrets");
  Farm farm("auth-routes", 0, token_args(secrets));
  const auto routes = test::openapi_routes(fs::path(TESSERA_SOURCE_DIR) / "docs" / "openapi.yaml");
  ASSERT_GE(routes.size(), 10u);
  // A registered worker's secret goes with every call: what is tested here is the token.
  HttpClient registrar = farm.http(10s);
  registrar.set_bearer_token(worker_token);
  const HttpResult registered = registrar.request(
      "POST", "/v1/workers", json{{"name", "w"}, {"protocol", kWorkerProtocolVersion}}.dump());
  ASSERT_EQ(registered.status, 201) << registered.body;
  const HttpClient::Headers secret = {
      {"X-Tessera-Worker-Secret", json::parse(registered.body)["secret"].get<std::string>()}};
  const auto call = [&](const std::string& method, const std::string& path,
                        const std::string& token) {
    HttpClient http = farm.http(10s);
    http.set_bearer_token(token);
    return http.request(method, concrete(path), method == "GET" || method == "DELETE" ? "" : "{}",
                        "application/json", secret);
  };
  for (const auto& [route, role] : routes) {
    const auto& [method, path] = route;
    SCOPED_TRACE(method + " " + path + " (" + role + ")");
    if (role == "public") {
      EXPECT_EQ(call(method, path, "").status, 200);
      continue;
    }
    if (role == "metrics") {
      // Without --metrics-token, open to this machine (FarmMetrics tests the token).
      EXPECT_EQ(call(method, path, "").status, 200);
      continue;
    }
    ASSERT_TRUE(role == "client" || role == "worker");
    const std::string& own = role == "client" ? api_token : worker_token;
    const std::string& other = role == "client" ? worker_token : api_token;
    const HttpResult none = call(method, path, "");
    EXPECT_EQ(none.status, 401) << none.body;
    EXPECT_NE(none.body.find("missing_token"), std::string::npos) << none.body;
    EXPECT_EQ(none.headers.count("www-authenticate"), 1u);
    const HttpResult wrong = call(method, path, own + "x");
    EXPECT_EQ(wrong.status, 401) << wrong.body;
    EXPECT_NE(wrong.body.find("invalid_token"), std::string::npos) << wrong.body;
    const HttpResult crossed = call(method, path, other);
    EXPECT_EQ(crossed.status, 403) << crossed.body;
    EXPECT_NE(crossed.body.find("wrong_role"), std::string::npos) << crossed.body;
    // Its own token gets past the check (to whatever the dummy request deserves). The
    // farm's event stream does not end: its first piece is enough.
    if (path == "/v1/events") {
      HttpClient http = farm.http(10s);
      http.set_bearer_token(own);
      EXPECT_EQ(http.stream(path, [](std::string_view) { return false; }).status, 200);
      continue;
    }
    const HttpResult allowed = call(method, path, own);
    EXPECT_NE(allowed.status, 401) << allowed.body;
    EXPECT_NE(allowed.status, 403) << allowed.body;
  }
  // Refused from the headers: a stranger cannot make the server take in a body.
  EXPECT_EQ(status_for_header_only(
                farm.port(),
                "POST /v1/jobs HTTP/1.1\r\nHost: t\r\nContent-Type: application/json\r\n"
                "Content-Length: 1073741824\r\n\r\n"),
            401);
  EXPECT_EQ(
      status_for_header_only(
          farm.port(), "PUT /v1/leases/l-x/result HTTP/1.1\r\nHost: t\r\nAuthorization: Bearer " +
                           api_token + "\r\nContent-Length: 1073741824\r\n\r\n"),
      403);
  // The server kept serving, and logged no secret.
  HttpClient http = farm.http(10s);
  const HttpResult health = http.request("GET", "/healthz");
  EXPECT_EQ(health.status, 200);
  // Said to anyone, as a 401 would: the dashboard asks for the token before any call.
  EXPECT_EQ(nlohmann::json::parse(health.body)["api_token_required"], true) << health.body;
  const std::string log = test::read_text(farm.dir() / "server.log");
  EXPECT_EQ(log.find(api_token), std::string::npos);
  EXPECT_EQ(log.find(worker_token), std::string::npos);
}

// The command line of a process, its arguments joined by spaces.
std::string command_line(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::replace(text.begin(), text.end(), '\0', ' ');
  return text;
}

TEST(FarmAuthTest, WorkersWithTheTokenRenderAndTheTokenStaysOutOfProcessLists) {
  const fs::path secrets = test::fresh_dir("auth-render-secrets");
  Farm farm("auth-render", 1, token_args(secrets));
  farm.use_api_token(api_token);
  const std::string log = test::read_text(farm.dir() / "server.log");
  EXPECT_NE(log.find("the worker token file " + (secrets / "worker.token").string() +
                     " may be read by others than its owner (mode 0644): chmod 600"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("the API token file"), std::string::npos) << log;
  // An external worker with its token in a file, and one with a wrong token.
  test::write_text(secrets / "wrong.token", "not-the-token\n");
  auto outsider = std::make_unique<test::Process>(
      TESSERA_WORKER_BIN,
      std::vector<std::string>{"--server", farm.url(), "--threads", "1", "--name", "outsider",
                               "--token-file", (secrets / "wrong.token").string()},
      farm.dir() / "outsider.log");
  auto insider = std::make_unique<test::Process>(
      TESSERA_WORKER_BIN,
      std::vector<std::string>{"--server", farm.url(), "--threads", "1", "--name", "insider",
                               "--token-file", (secrets / "worker.token").string()},
      farm.dir() / "insider.log");
  const auto refused = outsider->wait_for(20s);
  ASSERT_TRUE(refused.has_value()) << "a worker with a wrong token kept running";
  EXPECT_TRUE(WIFEXITED(*refused) && WEXITSTATUS(*refused) != 0);
  EXPECT_NE(test::read_text(farm.dir() / "outsider.log").find("401"), std::string::npos);

  const json scene = test::small_showcase(32);
  const std::string id = farm.api().submit("with tokens", 50, scene)["id"];
  const json done = farm.wait_finished(id);
  ASSERT_EQ(done["state"], "completed") << done.dump();
  EXPECT_TRUE(test::same_pixels(test::farm_image(farm, id), test::render_image(scene, 2)));
  ASSERT_TRUE(farm.worker_named("local-1").has_value()) << "the local worker did not join";
  ASSERT_TRUE(farm.worker_named("insider").has_value());
  EXPECT_FALSE(farm.worker_named("outsider").has_value());

  // Nothing that `ps` shows holds a token: the server's and its local worker's commands.
  const std::vector<pid_t> locals = test::children_of(farm.server().pid());
  ASSERT_EQ(locals.size(), 1u);
  for (const pid_t pid : {farm.server().pid(), locals[0], insider->pid()}) {
    const std::string command = command_line(pid);
    EXPECT_FALSE(command.empty());
    EXPECT_EQ(command.find(api_token), std::string::npos) << command;
    EXPECT_EQ(command.find(worker_token), std::string::npos) << command;
  }
  // The CLI takes the API token from the environment too, and without it is refused.
  const test::CliRun without = test::run_cli(farm.dir(), {"--server", farm.url(), "list"});
  EXPECT_EQ(without.exit_code, 1) << without.output;
  EXPECT_NE(without.output.find("needs an API token: set TESSERA_API_TOKEN, or pass --token-file"),
            std::string::npos)
      << without.output;
  ::setenv("TESSERA_API_TOKEN", api_token.c_str(), 1);
  const test::CliRun with = test::run_cli(farm.dir(), {"--server", farm.url(), "list"});
  ::unsetenv("TESSERA_API_TOKEN");
  EXPECT_EQ(with.exit_code, 0) << with.output;
  EXPECT_NE(with.output.find(id.substr(0, 10)), std::string::npos) << with.output;
}

TEST(FarmAuthTest, BeyondLoopbackOnlyWithTokensOrInsecure) {
  const fs::path dir = test::fresh_dir("auth-listen");
  const auto start = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args{
        "--listen",        "0.0.0.0:0", "--data-dir",  (dir / name).string(),
        "--local-workers", "0",         "--port-file", (dir / (name + ".port")).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return std::make_unique<test::Process>(TESSERA_SERVER_BIN, args, dir / (name + ".log"));
  };
  auto open = start("open", {});
  const auto status = open->wait_for(20s);
  ASSERT_TRUE(status.has_value()) << "it listened on every interface without tokens";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 2) << "status " << *status;
  const std::string why = test::read_text(dir / "open.log");
  EXPECT_NE(why.find("--api-token"), std::string::npos) << why;
  EXPECT_NE(why.find("--insecure"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(dir / "open.port"));

  auto half = start("half", {"--worker-token", "w"});  // one token is not enough
  const auto half_status = half->wait_for(20s);
  ASSERT_TRUE(half_status.has_value());
  EXPECT_TRUE(WIFEXITED(*half_status) && WEXITSTATUS(*half_status) == 2);

  for (const auto& [name, extra] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"insecure", {"--insecure"}}, {"tokens", token_args(dir / "secrets")}}) {
    SCOPED_TRACE(name);
    auto server = start(name, extra);
    ASSERT_TRUE(test::eventually([&] { return fs::exists(dir / (name + ".port")); }, 20s))
        << test::read_text(dir / (name + ".log"));
    int port = 0;
    std::ifstream(dir / (name + ".port")) >> port;
    HttpClient http("http://127.0.0.1:" + std::to_string(port), 10s);
    EXPECT_EQ(http.request("GET", "/healthz").status, 200);
    server->signal(SIGTERM);
    EXPECT_TRUE(server->wait_for(20s).has_value());
  }
  EXPECT_NE(test::read_text(dir / "insecure.log").find("open to anyone"), std::string::npos);
}

}  // namespace
}  // namespace tessera
