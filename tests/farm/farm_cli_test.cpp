// The `tessera` job commands as a user runs them: a real process against a real farm, its
// exit code and what it printed (stdout and stderr, through the Process log file, so stdout
// is never a terminal here). The exit codes are the contract of README.md: 0 done, 1 the
// job failed or was canceled or the server refused, 2 usage or invalid scene, 3 unreachable.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <regex>

#include <gtest/gtest.h>

#include "tests/farm/farm_fixture.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using test::CliRun;
using test::contains;
using test::Farm;

// The CLI against `farm`, with its server URL.
CliRun tessera_cli(Farm& farm, std::vector<std::string> args,
                   std::chrono::milliseconds limit = 30s) {
  args.insert(args.begin(), {"--server", farm.url()});
  return test::run_cli(farm.dir(), args, limit);
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// A loopback port on which nothing listens, for as long as this object lives: the socket
// is bound (so no one else gets the port) but never listens, so connecting is refused.
class ClosedPort {
 public:
  ClosedPort() : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0)
      throw std::runtime_error("cannot reserve a port");
    port_ = ntohs(address.sin_port);
  }
  ~ClosedPort() { ::close(fd_); }
  int port() const { return port_; }

 private:
  int fd_;
  int port_ = 0;
};

TEST(FarmCliTest, JobCommandsEndToEnd) {
  Farm farm("cli-commands", 0);  // no workers until the test starts one: jobs wait as queued
  const json scene = test::showcase(64, 48, 2, 16);
  const fs::path scene_file = farm.dir() / "scene.json";
  test::write_text(scene_file, scene.dump());

  // An invalid scene is refused on this side, with its JSON Pointer, and nothing is sent.
  json bad_scene = scene;
  bad_scene["objects"][1]["radius"] = -1;
  const fs::path bad_file = farm.dir() / "bad.json";
  test::write_text(bad_file, bad_scene.dump());
  const CliRun bad = tessera_cli(farm, {"submit", bad_file.string()});
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_TRUE(contains(bad.output, "/objects/1/radius")) << bad.output;
  const fs::path broken_file = farm.dir() / "broken.json";
  test::write_text(broken_file, "{\"image\": ");
  EXPECT_EQ(tessera_cli(farm, {"submit", broken_file.string()}).exit_code, 2);
  EXPECT_TRUE(farm.api().jobs("", 100)["jobs"].empty()) << "an invalid scene reached the server";

  // submit without --wait prints the job id and returns at once.
  const CliRun submitted = tessera_cli(farm, {"submit", scene_file.string()});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  std::smatch match;
  ASSERT_TRUE(
      std::regex_search(submitted.output, match, std::regex(R"(submitted (\S+) \(scene\))")))
      << submitted.output;
  const std::string id = match[1];
  EXPECT_EQ(farm.api().job(id)["state"], "queued");

  const CliRun status = tessera_cli(farm, {"status", id});
  EXPECT_EQ(status.exit_code, 0) << status.output;
  EXPECT_TRUE(contains(status.output, id) && contains(status.output, "queued")) << status.output;
  const CliRun status_json = tessera_cli(farm, {"--json", "status", id});
  ASSERT_EQ(status_json.exit_code, 0) << status_json.output;
  const json status_reply = json::parse(status_json.output);
  EXPECT_EQ(status_reply["id"], id);
  EXPECT_EQ(status_reply["tiles"]["total"], 12);

  // A second job, submitted with --json, canceled while queued.
  const CliRun other =
      tessera_cli(farm, {"--json", "submit", scene_file.string(), "--name", "other"});
  ASSERT_EQ(other.exit_code, 0) << other.output;
  const json other_job = json::parse(other.output);
  const std::string other_id = other_job["id"];
  EXPECT_EQ(other_job["name"], "other");
  const CliRun canceled = tessera_cli(farm, {"cancel", other_id});
  EXPECT_EQ(canceled.exit_code, 0) << canceled.output;
  EXPECT_TRUE(contains(canceled.output, "canceled")) << canceled.output;
  EXPECT_EQ(farm.api().job(other_id)["state"], "canceled");
  const CliRun cancel_again = tessera_cli(farm, {"cancel", other_id});
  EXPECT_EQ(cancel_again.exit_code, 1) << cancel_again.output;
  EXPECT_EQ(tessera_cli(farm, {"watch", other_id}).exit_code, 1) << "watching a canceled job";

  // watch follows the job to completion in plain lines: stdout is a file here.
  const auto worker = farm.start_worker("cli-worker", 1);
  const CliRun watched = tessera_cli(farm, {"watch", id}, 60s);
  EXPECT_EQ(watched.exit_code, 0) << watched.output;
  EXPECT_FALSE(contains(watched.output, "\r") || contains(watched.output, "\033"))
      << "terminal control codes in plain output: " << watched.output;
  const std::vector<std::string> watch_lines = lines_of(watched.output);
  ASSERT_FALSE(watch_lines.empty());
  EXPECT_EQ(watch_lines.back().rfind("completed 12/12 tiles", 0), 0u) << watched.output;
  EXPECT_EQ(farm.api().job(id)["state"], "completed");

  const CliRun listed = tessera_cli(farm, {"list"});
  EXPECT_EQ(listed.exit_code, 0) << listed.output;
  // The table shows ids as far as they tell jobs apart (any unique prefix names a job).
  EXPECT_TRUE(contains(listed.output, id.substr(0, 10) + " ") &&
              contains(listed.output, other_id.substr(0, 10) + " "))
      << listed.output;
  const CliRun completed = tessera_cli(farm, {"list", "--state", "completed"});
  EXPECT_EQ(completed.exit_code, 0) << completed.output;
  EXPECT_TRUE(contains(completed.output, id.substr(0, 10))) << completed.output;
  EXPECT_FALSE(contains(completed.output, other_id.substr(0, 10))) << completed.output;
  const CliRun listed_json = tessera_cli(farm, {"--json", "list"});
  ASSERT_EQ(listed_json.exit_code, 0) << listed_json.output;
  EXPECT_EQ(json::parse(listed_json.output)["jobs"].size(), 2u);

  // The image: EXR bit for bit as a local render, and a real PNG.
  const fs::path exr = farm.dir() / "out.exr";
  const CliRun got_exr = tessera_cli(farm, {"get", id, "-o", exr.string()});
  ASSERT_EQ(got_exr.exit_code, 0) << got_exr.output;
  EXPECT_TRUE(contains(got_exr.output, "wrote ")) << got_exr.output;
  EXPECT_TRUE(test::same_pixels(read_image(exr), test::render_image(scene, 2)));
  const fs::path png = farm.dir() / "out.png";
  const CliRun got_png = tessera_cli(farm, {"get", id, "-o", png.string()});
  ASSERT_EQ(got_png.exit_code, 0) << got_png.output;
  EXPECT_EQ(test::read_text(png).substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const Image png_image = read_image(png);
  EXPECT_EQ(png_image.width(), 64);
  EXPECT_EQ(png_image.height(), 48);
  // Byte for byte the PNG that `tessera render` writes: the same pixels, the same encoder.
  const fs::path local_png = farm.dir() / "local.png";
  const CliRun rendered =
      test::run_cli(farm.dir(), {"render", scene_file.string(), "-o", local_png.string()});
  ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
  EXPECT_TRUE(test::read_text(local_png) == test::read_text(png)) << "the PNGs differ";
  EXPECT_EQ(tessera_cli(farm, {"get", id, "-o", (farm.dir() / "out.bmp").string()}).exit_code, 2);
  EXPECT_FALSE(fs::exists(farm.dir() / "out.bmp"));

  const CliRun workers = tessera_cli(farm, {"workers"});
  EXPECT_EQ(workers.exit_code, 0) << workers.output;
  EXPECT_TRUE(contains(workers.output, "cli-worker")) << workers.output;
  const CliRun workers_json = tessera_cli(farm, {"--json", "workers"});
  ASSERT_EQ(workers_json.exit_code, 0) << workers_json.output;
  const json worker_list = json::parse(workers_json.output)["workers"];
  ASSERT_EQ(worker_list.size(), 1u) << workers_json.output;
  EXPECT_EQ(worker_list[0]["name"], "cli-worker");
  EXPECT_EQ(worker_list[0]["tiles_rendered"], 12);

  // rm: the job is gone; asking for it again is a server refusal (1), not a usage error.
  const CliRun removed = tessera_cli(farm, {"rm", other_id});
  EXPECT_EQ(removed.exit_code, 0) << removed.output;
  EXPECT_TRUE(contains(removed.output, "removed " + other_id)) << removed.output;
  EXPECT_EQ(tessera_cli(farm, {"status", other_id}).exit_code, 1);
  EXPECT_EQ(tessera_cli(farm, {"rm", other_id}).exit_code, 1);
  const json left = farm.api().jobs("", 100)["jobs"];
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0]["id"], id);
}

TEST(FarmCliTest, SubmitWaitReportsACanceledJobWithExitOne) {
  Farm farm("cli-wait-cancel", 0);
  const fs::path scene_file = farm.dir() / "scene.json";
  test::write_text(scene_file, test::showcase(64, 48, 1, 16).dump());
  test::Process waiting(TESSERA_CLI_BIN,
                        {"--server", farm.url(), "submit", scene_file.string(), "--wait"},
                        farm.dir() / "wait.log");
  json jobs;
  ASSERT_TRUE(test::eventually(
      [&] {
        jobs = farm.api().jobs("", 10)["jobs"];
        return !jobs.empty();
      },
      20s));
  farm.api().cancel(jobs[0]["id"]);
  const auto status = waiting.wait_for(20s);
  ASSERT_TRUE(status.has_value()) << "submit --wait did not notice the cancel";
  EXPECT_TRUE(WIFEXITED(*status));
  EXPECT_EQ(WEXITSTATUS(*status), 1) << test::read_text(farm.dir() / "wait.log");
}

TEST(FarmCliTest, AnUnreachableServerExitsWithThree) {
  const fs::path dir = test::fresh_dir("cli-unreachable");
  const ClosedPort closed;
  const std::string url = "http://127.0.0.1:" + std::to_string(closed.port());
  for (const std::vector<std::string>& command :
       {std::vector<std::string>{"list"}, {"status", "j-none"}, {"workers"}}) {
    std::vector<std::string> args{"--server", url};
    args.insert(args.end(), command.begin(), command.end());
    const CliRun run = test::run_cli(dir, args);
    EXPECT_EQ(run.exit_code, 3) << command[0] << ": " << run.output;
    EXPECT_TRUE(contains(run.output, "cannot reach")) << run.output;
  }
  // A valid scene is checked first, then the server is found missing.
  const fs::path scene_file = dir / "scene.json";
  test::write_text(scene_file, test::showcase(64, 48, 1, 16).dump());
  EXPECT_EQ(test::run_cli(dir, {"--server", url, "submit", scene_file.string()}).exit_code, 3);
}

TEST(FarmCliTest, UsageErrorsExitWithTwo) {
  const fs::path dir = test::fresh_dir("cli-usage");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"status"}, {"list", "--limit", "0"}, {"frobnicate"}, {}}) {
    const CliRun run = test::run_cli(dir, args);
    EXPECT_EQ(run.exit_code, 2) << (args.empty() ? "(none)" : args[0]) << ": " << run.output;
  }
}

TEST(FarmCliTest, RoughEdges) {
  Farm farm("cli-edges", 0);
  const fs::path scene_file = farm.dir() / "scene.json";
  test::write_text(scene_file, test::showcase(32, 32, 1, 16).dump());
  const std::string id = farm.api().submit("queued", 50, test::showcase(32, 32, 1, 16))["id"];

  // The global options after the subcommand, as in git and kubectl.
  const CliRun listed = test::run_cli(farm.dir(), {"list", "--json", "--server", farm.url()});
  EXPECT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_EQ(json::parse(listed.output)["jobs"].size(), 1u) << listed.output;

  // An id is data in the path: a space or a slash names no job, and changes no request.
  for (const std::string odd : {"a b", "../jobs", "j\r\nX-Injected: 1", "%2e%2e"}) {
    const CliRun status = tessera_cli(farm, {"status", odd});
    EXPECT_EQ(status.exit_code, 1) << odd << ": " << status.output;
    EXPECT_TRUE(contains(status.output, "error: no job")) << status.output;
  }

  // get of an unfinished job names the option that gets it anyway.
  const fs::path out = farm.dir() / "out.png";
  const CliRun unfinished = tessera_cli(farm, {"get", id, "-o", out.string()});
  EXPECT_EQ(unfinished.exit_code, 1) << unfinished.output;
  EXPECT_TRUE(contains(unfinished.output, "--partial")) << unfinished.output;
  EXPECT_FALSE(contains(unfinished.output, "?partial")) << unfinished.output;
  EXPECT_FALSE(fs::exists(out.string() + ".part"));
  EXPECT_EQ(tessera_cli(farm, {"get", id, "--partial", "-o", out.string()}).exit_code, 0);

  // get to a directory, or to a path that cannot be written: a clear error, no .part left.
  const CliRun to_dir = tessera_cli(farm, {"get", id, "--partial", "-o", farm.dir().string()});
  EXPECT_EQ(to_dir.exit_code, 2) << to_dir.output;
  EXPECT_TRUE(contains(to_dir.output, "is a directory")) << to_dir.output;
  const fs::path nowhere = farm.dir() / "no-such-dir" / "x.png";
  const CliRun unwritable = tessera_cli(farm, {"get", id, "--partial", "-o", nowhere.string()});
  EXPECT_EQ(unwritable.exit_code, 2) << unwritable.output;
  EXPECT_TRUE(contains(unwritable.output, "cannot write")) << unwritable.output;
  EXPECT_FALSE(fs::exists(nowhere.string() + ".part"));

  // A request the server refuses is 1, as the README says.
  const CliRun refused = tessera_cli(farm, {"rm", id});  // not finished: 409
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
}

TEST(FarmCliTest, SubmitWithAnOutputWaitsForTheImage) {
  Farm farm("cli-submit-output", 1);
  const fs::path scene_file = farm.dir() / "scene.json";
  test::write_text(scene_file, test::showcase(32, 32, 1, 16).dump());
  const fs::path out = farm.dir() / "out.png";
  const CliRun run = tessera_cli(farm, {"submit", scene_file.string(), "-o", out.string()}, 60s);
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(fs::exists(out)) << "-o without --wait did not wait for the image: " << run.output;
}

}  // namespace
}  // namespace tessera
