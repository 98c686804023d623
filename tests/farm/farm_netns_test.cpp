// The farm across hosts: three network namespaces stand in for three machines. The
// coordinator's namespace holds a bridge (10.77.0.1/24) with a veth link to each worker's
// namespace (10.77.0.2 and 10.77.0.3). Nothing is bound to loopback across namespaces, so
// every request really crosses a link: a worker that only worked on 127.0.0.1 fails here.
//
// Needs root and iproute2. Every interface and address lives inside the namespaces this
// test creates; the host's own interfaces are never touched. Namespaces and processes are
// cleaned up by RAII, whatever the outcome.
#include <unistd.h>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

std::string find_ip() {
  for (const char* path : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"})
    if (::access(path, X_OK) == 0) return path;
  return "";
}

// Runs `ip ARGS...` to completion; true when it exits 0. Its output goes to `log`.
bool ip_command(const std::string& ip, const std::vector<std::string>& args, const fs::path& log) {
  std::string line = "$ ip";
  for (const auto& a : args) line += " " + a;
  std::ofstream(log, std::ios::app) << line << '\n';
  test::Process process(ip, args, log);
  const auto status = process.wait_for(20s);
  return status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0;
}

// Network namespaces this test created; deleted on destruction. The processes inside
// must be gone first: declare this before them so it is destroyed after them.
class Namespaces {
 public:
  Namespaces(std::string ip, fs::path log) : ip_(std::move(ip)), log_(std::move(log)) {}
  ~Namespaces() {
    for (auto it = names_.rbegin(); it != names_.rend(); ++it)
      ip_command(ip_, {"netns", "del", *it}, log_);
  }
  Namespaces(const Namespaces&) = delete;
  Namespaces& operator=(const Namespaces&) = delete;

  bool add(const std::string& name) {
    ip_command(ip_, {"netns", "del", name}, log_);  // a leftover of a killed run with this pid
    if (!ip_command(ip_, {"netns", "add", name}, log_)) return false;
    names_.push_back(name);
    return true;
  }

 private:
  std::string ip_;
  fs::path log_;
  std::vector<std::string> names_;
};

TEST(FarmNetnsTest, WorkersInOtherNamespacesRenderAJobTogether) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to create network namespaces";
  const std::string ip = find_ip();
  if (ip.empty()) GTEST_SKIP() << "needs iproute2 (`ip`); apt-get install iproute2";
  const fs::path dir = test::fresh_dir("netns");
  const fs::path setup_log = dir / "setup.log";

  const std::string tag = "tsr" + std::to_string(::getpid());
  const std::string coordinator = tag + "c", host_a = tag + "a", host_b = tag + "b";
  Namespaces namespaces(ip, setup_log);
  if (!namespaces.add(coordinator) || !namespaces.add(host_a) || !namespaces.add(host_b))
    GTEST_SKIP() << "`ip netns add` failed (no permission in this container?); see " << setup_log;

  // All created inside the namespaces (`ip -n`); a veth's peer is created directly in
  // its worker's namespace, so nothing ever appears in the host's namespace.
  const std::vector<std::vector<std::string>> links = {
      {"-n", coordinator, "link", "add", "br0", "type", "bridge"},
      {"-n", coordinator, "link", "add", "va", "type", "veth", "peer", "name", "eth0", "netns",
       host_a},
      {"-n", coordinator, "link", "add", "vb", "type", "veth", "peer", "name", "eth0", "netns",
       host_b},
  };
  for (const auto& command : links)
    if (!ip_command(ip, command, setup_log))
      GTEST_SKIP() << "this kernel or container cannot create veth/bridge links; see " << setup_log;
  const std::vector<std::vector<std::string>> configuration = {
      {"-n", coordinator, "link", "set", "va", "master", "br0"},
      {"-n", coordinator, "link", "set", "vb", "master", "br0"},
      {"-n", coordinator, "addr", "add", "10.77.0.1/24", "dev", "br0"},
      {"-n", host_a, "addr", "add", "10.77.0.2/24", "dev", "eth0"},
      {"-n", host_b, "addr", "add", "10.77.0.3/24", "dev", "eth0"},
      {"-n", coordinator, "link", "set", "lo", "up"},
      {"-n", coordinator, "link", "set", "br0", "up"},
      {"-n", coordinator, "link", "set", "va", "up"},
      {"-n", coordinator, "link", "set", "vb", "up"},
      {"-n", host_a, "link", "set", "lo", "up"},
      {"-n", host_a, "link", "set", "eth0", "up"},
      {"-n", host_b, "link", "set", "lo", "up"},
      {"-n", host_b, "link", "set", "eth0", "up"},
  };
  for (const auto& command : configuration)
    ASSERT_TRUE(ip_command(ip, command, setup_log)) << "network setup failed; see " << setup_log;

  // Off loopback and without tokens, the coordinator refuses to start, and says why.
  {
    test::Process open_server(
        ip,
        {"netns", "exec", coordinator, TESSERA_SERVER_BIN, "--listen", "10.77.0.1:0", "--data-dir",
         (dir / "open-data").string(), "--local-workers", "0"},
        dir / "open-server.log");
    const auto status = open_server.wait_for(20s);
    ASSERT_TRUE(status.has_value()) << "a coordinator without tokens listened on 10.77.0.1";
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 2) << "status " << *status;
    EXPECT_NE(test::read_text(dir / "open-server.log").find("--insecure"), std::string::npos);
  }

  // Tokens from files, so that no process list shows them.
  const std::string api_token = "api-" + std::to_string(::getpid()) + "-secret";
  const std::string worker_token = "worker-" + std::to_string(::getpid()) + "-secret";
  test::write_text(dir / "api.token", api_token + "\n");
  test::write_text(dir / "worker.token", worker_token + "\n");

  // The coordinator listens on its bridge address only, on an ephemeral port.
  const fs::path port_file = dir / "port";
  test::Process server(
      ip,
      {"netns", "exec", coordinator, TESSERA_SERVER_BIN, "--listen", "10.77.0.1:0", "--data-dir",
       (dir / "data").string(), "--local-workers", "0", "--port-file", port_file.string(),
       "--log-level", "info", "--api-token-file", (dir / "api.token").string(),
       "--worker-token-file", (dir / "worker.token").string()},
      dir / "server.log");
  ASSERT_TRUE(test::eventually([&] { return fs::exists(port_file); }, 20s))
      << "the server did not start; see " << (dir / "server.log");
  int port = 0;
  std::ifstream(port_file) >> port;
  const std::string url = "http://10.77.0.1:" + std::to_string(port);

  const auto start_worker = [&](const std::string& ns, const std::string& name) {
    return std::make_unique<test::Process>(
        ip,
        std::vector<std::string>{"netns", "exec", ns, TESSERA_WORKER_BIN, "--server", url,
                                 "--threads", "1", "--name", name, "--token-file",
                                 (dir / "worker.token").string()},
        dir / (name + ".log"));
  };
  const auto worker_a = start_worker(host_a, "host-a");
  const auto worker_b = start_worker(host_b, "host-b");

  // The test talks to the coordinator as a client on host b would: the CLI in that namespace.
  const std::vector<std::string> on_host_b{ip, "netns", "exec", host_b};
  const auto workers = [&] {
    const test::CliRun run = test::run_cli(
        dir, {"--server", url, "--token-file", (dir / "api.token").string(), "--json", "workers"},
        30s, on_host_b);
    if (run.exit_code != 0) return json::array();
    const json reply = json::parse(run.output, nullptr, false);
    return reply.is_discarded() ? json::array() : reply["workers"];
  };
  // Both registered (and so parked in a claim) before there is work, so both get a share.
  json registered;
  ASSERT_TRUE(test::eventually(
      [&] {
        registered = workers();
        return registered.size() == 2;
      },
      30s))
      << registered.dump() << "; see the logs in " << dir;

  const json scene = test::showcase(160, 120, 2, 16);  // 80 tiles
  const fs::path scene_file = dir / "scene.json";
  test::write_text(scene_file, scene.dump());
  const fs::path image_file = dir / "out.exr";
  const test::CliRun submitted =
      test::run_cli(dir,
                    {"--server", url, "--token-file", (dir / "api.token").string(), "submit",
                     scene_file.string(), "--wait", "-o", image_file.string()},
                    60s, on_host_b);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  EXPECT_TRUE(test::same_pixels(read_image(image_file), test::render_image(scene, 2)));

  const json done = workers();
  ASSERT_EQ(done.size(), 2u) << done.dump();
  int total = 0;
  for (const json& worker : done) {
    EXPECT_GT(worker["tiles_rendered"].get<int>(), 0) << worker.dump();
    total += worker["tiles_rendered"].get<int>();
  }
  EXPECT_EQ(total, 80) << done.dump();
  // Without the token, a client on the other host is turned away.
  const test::CliRun stranger = test::run_cli(dir, {"--server", url, "list"}, 30s, on_host_b);
  EXPECT_EQ(stranger.exit_code, 1) << stranger.output;
  EXPECT_NE(stranger.output.find("token"), std::string::npos) << stranger.output;
  // And no log holds a secret.
  for (const char* log : {"server.log", "host-a.log", "host-b.log"}) {
    const std::string text = test::read_text(dir / log);
    EXPECT_EQ(text.find(api_token), std::string::npos) << log;
    EXPECT_EQ(text.find(worker_token), std::string::npos) << log;
  }
}

}  // namespace
}  // namespace tessera
