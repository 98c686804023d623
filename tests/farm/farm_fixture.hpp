// Shared by the farm's end-to-end tests: a real tessera-server on an ephemeral loopback
// port, tessera-worker and tessera (CLI) processes, and the comparisons the tests make.
// Every test directory is named after the test process's pid, so parallel runs (ctest -j)
// never share a data dir or a log.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/image/image_io.hpp"
#include "common/scene/scene_parser.hpp"
#include "tests/farm/json_api.hpp"
#include "tests/farm/process.hpp"
#include "tests/unit/worker/render_helpers.hpp"

namespace tessera::test {

namespace farm_fs = std::filesystem;

inline farm_fs::path fresh_dir(const std::string& name) {
  const farm_fs::path dir =
      farm_fs::temp_directory_path() / ("tessera-farm-" + std::to_string(::getpid()) + "-" + name);
  farm_fs::remove_all(dir);
  farm_fs::create_directories(dir);
  return dir;
}

inline std::string read_text(const farm_fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline void write_text(const farm_fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary)
      .write(text.data(), static_cast<std::streamsize>(text.size()));
}

// A coordinator with `workers` local worker processes on an ephemeral port.
class Farm {
 public:
  Farm(const std::string& name, int workers, const std::vector<std::string>& extra = {})
      : dir_(fresh_dir(name)) {
    using namespace std::chrono_literals;
    std::vector<std::string> args{"--listen",        "127.0.0.1:0",
                                  "--data-dir",      (dir_ / "data").string(),
                                  "--local-workers", std::to_string(workers),
                                  "--port-file",     (dir_ / "port").string(),
                                  "--log-level",     "warn"};
    // A test that names its own log level gets it instead.
    if (std::find(extra.begin(), extra.end(), "--log-level") != extra.end())
      args.resize(args.size() - 2);
    args.insert(args.end(), extra.begin(), extra.end());
    server_ = std::make_unique<Process>(TESSERA_SERVER_BIN, args, dir_ / "server.log");
    const bool up = eventually([&] { return farm_fs::exists(dir_ / "port"); }, 20s);
    if (!up)
      throw std::runtime_error("server did not start; see " + (dir_ / "server.log").string());
    std::ifstream(dir_ / "port") >> port_;
    api_ = std::make_unique<JsonApi>(url());
  }
  ~Farm() {
    using namespace std::chrono_literals;
    if (server_) {
      server_->signal(SIGTERM);
      server_->wait_for(20s);
    }
  }
  Farm(const Farm&) = delete;
  Farm& operator=(const Farm&) = delete;

  // For a coordinator started with --api-token: api() sends it from now on.
  void use_api_token(const std::string& token) { api_ = std::make_unique<JsonApi>(url(), token); }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  // A client of this farm whose every answer is checked against docs/openapi.yaml.
  HttpClient http(std::chrono::milliseconds timeout) const {
    HttpClient client(url(), timeout);
    client.set_observer(contract_observer());
    return client;
  }
  int port() const { return port_; }
  JsonApi& api() { return *api_; }
  Process& server() { return *server_; }
  const farm_fs::path& dir() const { return dir_; }

  nlohmann::json wait_finished(const std::string& id,
                               std::chrono::milliseconds limit = std::chrono::seconds(60)) {
    nlohmann::json job;
    eventually(
        [&] {
          job = api_->job(id);
          const std::string state = job["state"];
          return state == "completed" || state == "failed" || state == "canceled";
        },
        limit);
    return job;
  }

  // A tessera-worker process of this farm; its log is WORKER_NAME.log in the farm's dir.
  std::unique_ptr<Process> start_worker(const std::string& worker_name, int threads = 1) {
    return std::make_unique<Process>(
        TESSERA_WORKER_BIN,
        std::vector<std::string>{"--server", url(), "--threads", std::to_string(threads), "--name",
                                 worker_name, "--log-level", "info"},
        dir_ / (worker_name + ".log"));
  }

  // The worker of that name in GET /v1/workers, if there is one.
  std::optional<nlohmann::json> worker_named(const std::string& worker_name) {
    const nlohmann::json reply = api_->workers();  // named: a range-for would not extend its life
    for (const nlohmann::json& worker : reply["workers"])
      if (worker["name"] == worker_name) return worker;
    return std::nullopt;
  }

 private:
  farm_fs::path dir_;
  int port_ = 0;
  std::unique_ptr<Process> server_;
  std::unique_ptr<JsonApi> api_;
};

// The pids of a process's children, from /proc.
inline std::vector<pid_t> children_of(pid_t parent) {
  std::vector<pid_t> children;
  for (const auto& entry : farm_fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string text;
    std::getline(stat, text);
    const auto close = text.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(text.substr(close + 2));
    char state = 0;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid == parent && state != 'Z') children.push_back(std::stoi(name));
  }
  return children;
}

// What a worker said it rendered in its last log line ("... after rendering N tiles");
// -1 when it said nothing of the kind.
inline int tiles_rendered_by(const farm_fs::path& log) {
  const std::string text = read_text(log);
  static const std::regex line("after rendering ([0-9]+) tiles");
  int count = -1;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), line); it != std::sregex_iterator();
       ++it)
    count = std::stoi((*it)[1]);
  return count;
}

// The port a coordinator started with --port-file DIR/port wrote there, once it has (0 if
// it has not within 30 s, after a test failure that shows its `log`).
inline int port_from_file(const farm_fs::path& dir, const farm_fs::path& log) {
  using namespace std::chrono_literals;
  EXPECT_TRUE(eventually(
      [&] { return farm_fs::exists(dir / "port") && farm_fs::file_size(dir / "port") > 0; }, 30s))
      << read_text(log);
  int port = 0;
  std::ifstream(dir / "port") >> port;
  return port;
}

// A coordinator without local workers on `dir`'s data directory, listening on `listen`
// (an ephemeral port, or the port of one before it: a test kills it and starts another on
// the same store and address), logging to `log` in `dir`; with the port it took.
inline std::pair<std::unique_ptr<Process>, int> start_coordinator(const farm_fs::path& dir,
                                                                  const std::string& listen,
                                                                  const std::string& log) {
  using namespace std::chrono_literals;
  farm_fs::remove(dir / "port");
  auto server = std::make_unique<Process>(
      TESSERA_SERVER_BIN,
      std::vector<std::string>{"--listen", listen, "--data-dir", (dir / "data").string(),
                               "--local-workers", "0", "--port-file", (dir / "port").string(),
                               "--log-level", "info"},
      dir / log);
  const int port = port_from_file(dir, dir / log);
  return {std::move(server), port};
}

// The showcase scene at a size, sampling and tile size small enough for a test.
inline nlohmann::json showcase(int width, int height, int spp, int tile_size) {
  nlohmann::json scene =
      read_json_file(farm_fs::path(TESSERA_SOURCE_DIR) / "examples" / "showcase.json");
  scene["image"] = {{"width", width}, {"height", height}};
  scene["render"]["samples_per_pixel"] = spp;
  scene["render"]["tile_size"] = tile_size;
  return scene;
}

inline nlohmann::json small_showcase(int tile_size) { return showcase(120, 90, 2, tile_size); }

inline Image farm_image(Farm& farm, const std::string& id) {
  const farm_fs::path path = farm.dir() / (id + ".exr");
  write_text(path, farm.api().image(id, "exr", false));
  return read_image(path);
}

// Bit for bit: the farm must assemble exactly the floats a single machine computes.
inline ::testing::AssertionResult same_pixels(const Image& actual, const Image& expected) {
  if (actual.width() != expected.width() || actual.height() != expected.height())
    return ::testing::AssertionFailure()
           << actual.width() << "x" << actual.height() << " instead of " << expected.width() << "x"
           << expected.height();
  if (std::memcmp(actual.pixels().data(), expected.pixels().data(),
                  expected.pixels().size_bytes()) == 0)
    return ::testing::AssertionSuccess();
  // Enough to tell a tile that never arrived (black where the render is not) from pixels
  // rendered otherwise (a small difference), should this ever fail.
  int differ = 0, black = 0, first_x = -1, first_y = -1;
  float largest = 0;
  for (int y = 0; y < actual.height(); ++y)
    for (int x = 0; x < actual.width(); ++x) {
      const float* a = actual.pixel(x, y);
      const float* e = expected.pixel(x, y);
      if (std::memcmp(a, e, 3 * sizeof(float)) == 0) continue;
      if (differ++ == 0) first_x = x, first_y = y;
      black += a[0] == 0.0f && a[1] == 0.0f && a[2] == 0.0f;
      for (int c = 0; c < 3; ++c) largest = std::max(largest, std::fabs(a[c] - e[c]));
    }
  return ::testing::AssertionFailure()
         << "pixels differ from the local render: " << differ << " of "
         << actual.width() * actual.height() << " pixels, " << black
         << " of them black, the first at (" << first_x << ", " << first_y
         << "), the largest difference " << largest;
}

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Runs a command to completion; true when it exited 0.
inline bool run_command(const std::string& binary, const std::vector<std::string>& args,
                        const farm_fs::path& log) {
  Process process(binary, args, log);
  const auto status = process.wait_for(std::chrono::seconds(20));
  return status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0;
}

// A file system of `size` bytes (mount's size=, "2m") on `dir` while it lives, for tests of
// a full disk: a tmpfs, which needs root. mounted() says whether it is there; why not is in
// `dir`'s sibling mount.log.
class SmallDisk {
 public:
  SmallDisk(const farm_fs::path& dir, const std::string& size) : dir_(dir) {
    farm_fs::create_directories(dir);
    mounted_ =
        ::geteuid() == 0 &&
        run_command("/bin/mount", {"-t", "tmpfs", "-o", "size=" + size, "tmpfs", dir.string()},
                    dir.parent_path() / "mount.log");
  }
  ~SmallDisk() {
    if (mounted_)
      run_command("/bin/umount", {"-l", dir_.string()}, dir_.parent_path() / "umount.log");
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;
  bool mounted() const { return mounted_; }

 private:
  farm_fs::path dir_;
  bool mounted_ = false;
};

// A finished tessera CLI run: its exit code and everything it printed (stdout and stderr).
struct CliRun {
  int exit_code = -1;
  std::string output;
};

// Runs `tessera ARGS...` to completion, logging into a fresh file under `dir`. A CLI that
// has not exited after `limit` is killed and reported with exit code -1.
inline CliRun run_cli(const farm_fs::path& dir, const std::vector<std::string>& args,
                      std::chrono::milliseconds limit = std::chrono::seconds(30),
                      const std::vector<std::string>& prefix = {}) {
  static int counter = 0;
  const farm_fs::path log = dir / ("cli-" + std::to_string(++counter) + ".log");
  std::optional<int> status;
  {
    std::vector<std::string> argv = prefix;
    std::string binary = TESSERA_CLI_BIN;
    if (!prefix.empty()) {
      binary = prefix.front();
      argv.erase(argv.begin());
      argv.push_back(TESSERA_CLI_BIN);
    }
    argv.insert(argv.end(), args.begin(), args.end());
    Process cli(binary, argv, log);
    status = cli.wait_for(limit);
  }
  CliRun run;
  run.output = read_text(log);
  if (status && WIFEXITED(*status)) run.exit_code = WEXITSTATUS(*status);
  return run;
}

}  // namespace tessera::test
