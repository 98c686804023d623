// deploy/docker/Dockerfile builds the image the way CI builds the project: the README's
// install script and its configure and build commands, word for word, so that the image
// cannot drift from what the test suite checked. No container engine runs here, so the
// Dockerfile is read, not built.
#include <algorithm>
#include <regex>

#include <gtest/gtest.h>

#include "tests/deploy/deploy_support.hpp"

namespace tessera {
namespace {

struct Instruction {
  std::string keyword;  // upper case: FROM, RUN, COPY...
  std::string arguments;
};

struct Stage {
  std::string base;  // FROM's image
  std::string name;  // after AS
  std::vector<Instruction> instructions;
};

std::string squeeze(const std::string& text) {
  std::string out;
  for (char c : text) {
    const bool space = c == ' ' || c == '\t' || c == '\n';
    if (space && (out.empty() || out.back() == ' ')) continue;
    out += space ? ' ' : c;
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

// The Dockerfile's stages; continuation lines joined, comments dropped.
std::vector<Stage> dockerfile_stages() {
  std::vector<Stage> stages;
  std::string pending;
  const auto finish = [&stages](const std::string& line) {
    const std::string text = squeeze(line);
    if (text.empty()) return;
    const auto space = text.find(' ');
    Instruction instruction{text.substr(0, space),
                            space == std::string::npos ? "" : text.substr(space + 1)};
    std::transform(instruction.keyword.begin(), instruction.keyword.end(),
                   instruction.keyword.begin(), ::toupper);
    if (instruction.keyword == "FROM") {
      std::smatch match;
      static const std::regex from(R"((\S+)(?: [Aa][Ss] (\S+))?)");
      std::regex_match(instruction.arguments, match, from);
      stages.push_back({match[1], match[2], {}});
    } else if (!stages.empty()) {
      stages.back().instructions.push_back(instruction);
    }
  };
  for (const std::string& raw : test::source_lines("deploy/docker/Dockerfile")) {
    const std::string line = squeeze(raw);
    if (line.empty() || line[0] == '#') continue;
    if (line.back() == '\\') {
      pending += line.substr(0, line.size() - 1) + " ";
      continue;
    }
    finish(pending + line);
    pending.clear();
  }
  finish(pending);
  return stages;
}

std::vector<std::string> split_steps(const std::string& command) {
  std::vector<std::string> steps;
  std::size_t start = 0;
  for (std::size_t at; (at = command.find(" && ", start)) != std::string::npos; start = at + 4)
    steps.push_back(squeeze(command.substr(start, at - start)));
  steps.push_back(squeeze(command.substr(start)));
  return steps;
}

// The README's test command, taken the way .ci/run takes it: CI runs this very line.
std::string readme_test_command() {
  const auto command = test::find_in_source(".ci/run", R"(test_command='([^']+)')");
  if (!command) throw std::runtime_error(".ci/run no longer sets test_command='...'");
  return *command;
}

// The steps before the tests run: install the packages, configure, build.
std::vector<std::string> readme_build_steps() {
  std::vector<std::string> steps = split_steps(readme_test_command());
  const auto tests = std::find_if(steps.begin(), steps.end(), [](const std::string& step) {
    return step.rfind("ctest", 0) == 0;
  });
  steps.erase(tests, steps.end());
  return steps;
}

TEST(DeployDockerTest, TheReadmeShowsTheCommandCiRuns) {
  EXPECT_NE(test::read_source("README.md").find(readme_test_command()), std::string::npos);
  const auto steps = readme_build_steps();
  ASSERT_EQ(steps.size(), 3u) << "expected install, configure, build before ctest";
  EXPECT_EQ(steps[0], "bash deploy/install-deps.sh");
}

TEST(DeployDockerTest, TheBuildStageRunsTheReadmesSteps) {
  const auto stages = dockerfile_stages();
  ASSERT_EQ(stages.size(), 2u) << "a build stage and a runtime stage";
  const Stage& build = stages[0];
  EXPECT_EQ(build.base, "debian:bookworm") << "the README's distribution: Debian 12";
  std::vector<std::string> steps;
  for (const Instruction& instruction : build.instructions)
    if (instruction.keyword == "RUN")
      for (const std::string& step : split_steps(instruction.arguments)) steps.push_back(step);
  EXPECT_EQ(steps, readme_build_steps())
      << "the image must be built exactly as the README (and CI) builds: same install script, "
         "same cmake configure and build";
  // The install script is the repository's own, copied before it runs.
  bool copied = false;
  for (const Instruction& instruction : build.instructions) {
    if (instruction.keyword == "RUN") break;
    copied = copied || (instruction.keyword == "COPY" &&
                        instruction.arguments.find("deploy/install-deps.sh") != std::string::npos);
  }
  EXPECT_TRUE(copied) << "COPY deploy/install-deps.sh before running it";
}

TEST(DeployDockerTest, TheRuntimeStageHoldsTheThreeProgramsAsAPlainUser) {
  const auto stages = dockerfile_stages();
  ASSERT_EQ(stages.size(), 2u);
  const Stage& build = stages[0];
  const Stage& runtime = stages[1];
  EXPECT_EQ(runtime.base, "debian:bookworm-slim");
  std::string workdir;
  for (const Instruction& instruction : build.instructions)
    if (instruction.keyword == "WORKDIR") workdir = instruction.arguments;
  // The build directory the README configures (-B DIR).
  std::smatch match;
  const std::string configure = readme_build_steps().at(1);
  ASSERT_TRUE(std::regex_search(configure, match, std::regex(R"(-B (\S+))"))) << configure;
  const std::string build_dir = workdir + "/" + match[1].str() + "/";

  std::string copied_from_build, user, healthcheck, run_text, expose, cmd;
  for (const Instruction& instruction : runtime.instructions) {
    if (instruction.keyword == "COPY" &&
        instruction.arguments.rfind("--from=" + build.name + " ", 0) == 0)
      copied_from_build += instruction.arguments + " ";
    if (instruction.keyword == "USER") user = instruction.arguments;
    if (instruction.keyword == "HEALTHCHECK") healthcheck = instruction.arguments;
    if (instruction.keyword == "RUN") run_text += instruction.arguments + "\n";
    if (instruction.keyword == "EXPOSE") expose = instruction.arguments;
    if (instruction.keyword == "CMD") cmd = instruction.arguments;
  }
  for (const char* program : {"server/tessera-server", "worker/tessera-worker", "client/tessera"})
    EXPECT_NE(copied_from_build.find(build_dir + program + " "), std::string::npos)
        << program << " is not copied from " << build_dir;
  // The programs load the tracer and open the image-file module from ../lib/tessera/ beside
  // their own directory, /usr/local/bin: the whole folder, with the tracer's glibc-hwcaps/.
  EXPECT_NE(copied_from_build.find(build_dir + "lib/tessera/ /usr/local/lib/tessera/"),
            std::string::npos)
      << "lib/tessera/ is not copied to /usr/local/lib/tessera/";
  EXPECT_FALSE(user.empty()) << "the image must not run as root";
  EXPECT_EQ(user.find("root"), std::string::npos);
  EXPECT_NE(user.rfind("0", 0), 0u) << "uid 0 is root";
  // Only runtime libraries: nothing to build with, and not the build's install script.
  EXPECT_EQ(run_text.find("install-deps.sh"), std::string::npos);
  EXPECT_FALSE(std::regex_search(run_text, std::regex(R"(\S+-dev\b)"))) << run_text;
  EXPECT_EQ(run_text.find("build-essential"), std::string::npos);

  // The health check asks /healthz on the port the default command listens on.
  EXPECT_NE(healthcheck.find("CMD"), std::string::npos);
  EXPECT_NE(healthcheck.find("tessera-healthcheck"), std::string::npos) << healthcheck;
  const std::string script = test::read_source("deploy/docker/healthcheck.sh");
  EXPECT_NE(script.find("GET /healthz "), std::string::npos);
  ASSERT_TRUE(std::regex_search(cmd, match, std::regex(R"re("--listen", "0\.0\.0\.0:(\d+)")re")))
      << cmd;
  const std::string port = match[1];
  EXPECT_EQ(expose, port);
  EXPECT_NE(script.find("127.0.0.1:" + port), std::string::npos)
      << "the check's default port is not " << port;
}

TEST(DeployDockerTest, TheBuildContextLeavesOutBuildTreesHistoryAndTokens) {
  for (const char* path : {".git", "build", "build-asan", "deploy/secrets/api.token",
                           "deploy/k8s/worker.token", "deploy/.env", "tessera-data"})
    EXPECT_TRUE(test::ignored_by(".dockerignore", path, true))
        << path << " would be sent to the build";
  for (const char* path :
       {"CMakeLists.txt", "common/scene.cpp", "server/server_main.cpp", "tracer/tracer.cpp",
        "client/main.cpp", "tests/CMakeLists.txt", "examples/showcase.json", "bench/run",
        "deploy/install-deps.sh", "deploy/docker/healthcheck.sh"})
    EXPECT_FALSE(test::ignored_by(".dockerignore", path, true))
        << path << " is needed by the build";
}

}  // namespace
}  // namespace tessera
