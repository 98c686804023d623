// deploy/compose.yaml: a coordinator keeping its data dir in a named volume, a worker
// service that `docker compose up --scale worker=N` can multiply, and the tokens from
// secret files, never written into the file.
#include <gtest/gtest.h>

#include "tests/deploy/deploy_yaml.hpp"

namespace tessera {
namespace {

using test::flag_value;
using test::text_of;
using test::texts_of;

YAML::Node compose() { return test::load_yaml("deploy/compose.yaml").at(0); }

// "/run/secrets/NAME" for a secret the service is given (Compose's default target).
bool is_given_secret(const YAML::Node& service, const std::string& path) {
  for (const std::string& name : texts_of(service["secrets"]))
    if (path == "/run/secrets/" + name) return true;
  return false;
}

TEST(DeployComposeTest, TheCoordinatorKeepsItsDataInANamedVolume) {
  const YAML::Node file = compose();
  const YAML::Node coordinator = file["services"]["coordinator"];
  ASSERT_TRUE(test::is_map(coordinator)) << "no coordinator service";
  const auto command = texts_of(coordinator["command"]);
  ASSERT_FALSE(command.empty());
  EXPECT_EQ(command[0], "tessera-server");
  EXPECT_EQ(flag_value(command, "--local-workers").value_or(""), "0");
  const auto data_dir = flag_value(command, "--data-dir");
  ASSERT_TRUE(data_dir);
  bool on_named_volume = false;
  for (const std::string& volume : texts_of(coordinator["volumes"])) {
    const auto colon = volume.find(':');
    const std::string source = volume.substr(0, colon);
    // A named volume, declared at the top level; not a bind mount of a host path.
    if (colon != std::string::npos && volume.substr(colon + 1) == *data_dir &&
        file["volumes"][source].IsDefined() && source.find('/') == std::string::npos)
      on_named_volume = true;
  }
  EXPECT_TRUE(on_named_volume) << "--data-dir " << *data_dir << " is not on a named volume";

  const auto listen = flag_value(command, "--listen");
  ASSERT_TRUE(listen);
  const std::string port = std::to_string(test::port_of(*listen));
  ASSERT_TRUE(test::is_sequence(coordinator["ports"]));
  const std::string published = text_of(coordinator["ports"][0]);
  EXPECT_EQ(published.substr(published.rfind(':') + 1), port)
      << "the published port is not --listen's";
}

TEST(DeployComposeTest, TheWorkerServiceScales) {
  const YAML::Node file = compose();
  const YAML::Node worker = file["services"]["worker"];
  ASSERT_TRUE(test::is_map(worker)) << "no worker service";
  // Any of these would make a second replica collide with the first.
  EXPECT_FALSE(worker["container_name"].IsDefined());
  EXPECT_FALSE(worker["ports"].IsDefined());
  EXPECT_FALSE(worker["volumes"].IsDefined());
  const auto command = texts_of(worker["command"]);
  ASSERT_FALSE(command.empty());
  EXPECT_EQ(command[0], "tessera-worker");
  EXPECT_TRUE(flag_value(command, "--threads")) << "without --threads each worker takes every core";
  // The coordinator, by its service name, on the port it listens on.
  const auto coordinator_listen =
      flag_value(texts_of(file["services"]["coordinator"]["command"]), "--listen").value_or(":0");
  EXPECT_EQ(flag_value(command, "--server").value_or(""),
            "http://coordinator:" + std::to_string(test::port_of(coordinator_listen)));
  EXPECT_EQ(text_of(worker["image"]), text_of(file["services"]["coordinator"]["image"]));
  const int bound = test::worker_shutdown_bound_s();
  EXPECT_GE(test::duration_s(text_of(worker["stop_grace_period"])).value_or(0), bound)
      << "a worker may need " << bound << " s after SIGTERM (Compose's default is 10 s)";
  EXPECT_EQ(text_of(worker["depends_on"]["coordinator"]["condition"]), "service_healthy");
}

TEST(DeployComposeTest, TokensComeFromSecretFilesOnly) {
  const YAML::Node file = compose();
  const std::pair<const char*, std::vector<const char*>> uses[] = {
      {"coordinator", {"--api-token-file", "--worker-token-file"}}, {"worker", {"--token-file"}}};
  for (const auto& [name, flags] : uses) {
    const YAML::Node service = file["services"][name];
    const auto command = texts_of(service["command"]);
    EXPECT_TRUE(test::token_flags_in(command).empty())
        << name << " has a token on its command line";
    for (const char* flag : flags)
      EXPECT_TRUE(is_given_secret(service, flag_value(command, flag).value_or("")))
          << name << " " << flag << " is not one of its secrets";
    // An environment may name a token only through interpolation, from a .env file.
    std::vector<std::string> environment = texts_of(service["environment"]);  // KEY=VALUE
    if (test::is_map(service["environment"]))
      for (const auto& variable : service["environment"])
        environment.push_back(variable.first.as<std::string>() + "=" + text_of(variable.second));
    for (const std::string& entry : environment) {
      if (entry.find("TOKEN") != std::string::npos) {
        EXPECT_NE(entry.find("${"), std::string::npos) << name << ": a token written in: " << entry;
      }
    }
  }
  ASSERT_TRUE(test::is_map(file["secrets"]));
  for (const auto& secret : file["secrets"]) {
    const std::string path = text_of(secret.second["file"]);
    EXPECT_FALSE(path.empty()) << secret.first.as<std::string>() << " must come from a file";
    // Relative to deploy/; ignored by git and never sent to an image build.
    const std::string relative = path.rfind("./", 0) == 0 ? path.substr(2) : path;
    EXPECT_TRUE(test::ignored_by("deploy/.gitignore", relative))
        << path << " is not in deploy/.gitignore";
    EXPECT_TRUE(test::ignored_by(".dockerignore", "deploy/" + relative, true))
        << path << " is not in .dockerignore";
  }
}

}  // namespace
}  // namespace tessera
