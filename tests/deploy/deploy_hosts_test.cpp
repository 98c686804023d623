// Bare metal and clusters: the systemd units (deploy/systemd) run hardened, keep the data
// in a StateDirectory, take the tokens as credentials and give a worker time to stop; the
// Slurm batch file (deploy/slurm) runs one worker per node and warns it before the time
// limit. tests/deploy/systemd_verify.sh has systemd itself parse the units, where it can.
#include <iterator>
#include <map>
#include <regex>

#include <gtest/gtest.h>

#include "tests/deploy/deploy_support.hpp"

namespace tessera {
namespace {

// A unit file: "Section.Key" to its values, in order (a key may repeat), continuation
// lines joined.
using Unit = std::multimap<std::string, std::string>;

Unit read_unit(const std::string& relative) {
  Unit unit;
  std::string section, pending;
  for (const std::string& raw : test::source_lines(relative)) {
    std::string line = pending + raw;
    pending.clear();
    if (!line.empty() && line.back() == '\\') {
      pending = line.substr(0, line.size() - 1) + " ";
      continue;
    }
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line[0] == '[') {
      section = line.substr(1, line.find(']') - 1);
      continue;
    }
    const auto equals = line.find('=');
    if (equals != std::string::npos)
      unit.emplace(section + "." + line.substr(0, equals), line.substr(equals + 1));
  }
  return unit;
}

std::string last(const Unit& unit, const std::string& key) {
  const auto [begin, end] = unit.equal_range(key);
  return begin == end ? "" : std::prev(end)->second;
}

std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string word; in >> word;) out.push_back(word);
  return out;
}

// LoadCredential=NAME:PATH entries, by name.
std::map<std::string, std::string> credentials(const Unit& unit) {
  std::map<std::string, std::string> found;
  const auto [begin, end] = unit.equal_range("Service.LoadCredential");
  for (auto it = begin; it != end; ++it)
    found[it->second.substr(0, it->second.find(':'))] = it->second.substr(it->second.find(':') + 1);
  return found;
}

void expect_hardened(const Unit& unit, const std::string& name) {
  EXPECT_TRUE(last(unit, "Service.DynamicUser") == "yes" || !last(unit, "Service.User").empty())
      << name << ": runs as root";
  EXPECT_NE(last(unit, "Service.User"), "root") << name;
  EXPECT_EQ(last(unit, "Service.ProtectSystem"), "strict") << name;
  EXPECT_EQ(last(unit, "Service.ProtectHome"), "yes") << name;
  EXPECT_EQ(last(unit, "Service.PrivateTmp"), "yes") << name;
  EXPECT_NE(last(unit, "Service.NoNewPrivileges"), "no") << name;
  EXPECT_EQ(last(unit, "Service.Restart"), "on-failure") << name;
  EXPECT_EQ(last(unit, "Install.WantedBy"), "multi-user.target") << name;
}

// The token flags of ExecStart name credentials the unit loads from /etc/tessera.
void expect_token_credentials(const Unit& unit, const std::string& name,
                              const std::vector<std::string>& flags) {
  const auto exec = words(last(unit, "Service.ExecStart"));
  EXPECT_TRUE(test::token_flags_in(exec).empty()) << name << ": a token on the command line";
  EXPECT_TRUE(last(unit, "Service.Environment").find("TOKEN") == std::string::npos) << name;
  const auto loaded = credentials(unit);
  for (const std::string& flag : flags) {
    const std::string file = test::flag_value(exec, flag).value_or("");
    ASSERT_EQ(file.rfind("%d/", 0), 0u) << name << ": " << flag << " is not a credential (%d/NAME)";
    const auto credential = loaded.find(file.substr(3));
    ASSERT_NE(credential, loaded.end())
        << name << ": no LoadCredential=" << file.substr(3) << ":...";
    EXPECT_EQ(credential->second.rfind("/etc/tessera/", 0), 0u) << name;
  }
}

TEST(DeploySystemdTest, TheServerUnitIsHardenedAndKeepsItsDataInItsStateDirectory) {
  const std::string name = "deploy/systemd/tessera-server.service";
  const Unit unit = read_unit(name);
  expect_hardened(unit, name);
  const std::string state = last(unit, "Service.StateDirectory");
  ASSERT_FALSE(state.empty()) << "the data dir must be a StateDirectory";
  const auto exec = words(last(unit, "Service.ExecStart"));
  ASSERT_FALSE(exec.empty());
  EXPECT_EQ(exec[0], "/usr/local/bin/tessera-server");
  const std::string data_dir = test::flag_value(exec, "--data-dir").value_or("");
  EXPECT_TRUE(data_dir == "%S/" + state || data_dir == "${STATE_DIRECTORY}" ||
              data_dir == "/var/lib/" + state)
      << "--data-dir " << data_dir << " is not StateDirectory=" << state;
  EXPECT_EQ(test::flag_value(exec, "--local-workers").value_or(""), "0");
  expect_token_credentials(unit, name, {"--api-token-file", "--worker-token-file"});
  // Its filter forbids setrlimit, so the unit itself must give it room for connections.
  const std::string nofile = last(unit, "Service.LimitNOFILE");
  EXPECT_FALSE(nofile.empty()) << name << ": no LimitNOFILE (the default 1024 is too few)";
  if (!nofile.empty()) {
    EXPECT_GE(std::stoul(nofile), 65536u) << name;
  }
}

TEST(DeploySystemdTest, TheWorkerUnitIsHardenedAndHasTimeToStop) {
  const std::string name = "deploy/systemd/tessera-worker@.service";
  const Unit unit = read_unit(name);
  expect_hardened(unit, name);
  const auto exec = words(last(unit, "Service.ExecStart"));
  ASSERT_FALSE(exec.empty());
  EXPECT_EQ(exec[0], "/usr/local/bin/tessera-worker");
  EXPECT_TRUE(test::flag_value(exec, "--server")) << name;
  EXPECT_TRUE(test::flag_value(exec, "--threads")) << name;
  // Instances on one host must not share a name in `tessera workers`.
  EXPECT_NE(test::flag_value(exec, "--name").value_or("").find("%i"), std::string::npos) << name;
  expect_token_credentials(unit, name, {"--token-file"});
  const int bound = test::worker_shutdown_bound_s();
  EXPECT_GE(test::duration_s(last(unit, "Service.TimeoutStopSec")).value_or(0), bound)
      << "a worker may need " << bound << " s after SIGTERM (systemd's default is 90 s)";
}

TEST(DeploySlurmTest, OneWorkerPerNodeWarnedBeforeTheTimeLimit) {
  const std::string name = "deploy/slurm/tessera-workers.sbatch";
  std::map<std::string, std::string> sbatch;  // #SBATCH --option=value
  static const std::regex directive(R"(^#SBATCH\s+(--[a-z-]+)(?:=(\S+))?)");
  std::string srun;
  for (const std::string& line : test::source_lines(name)) {
    std::smatch match;
    if (std::regex_search(line, match, directive)) sbatch[match[1]] = match[2];
    if (line.rfind("srun ", 0) == 0) srun = line;
  }
  EXPECT_EQ(sbatch["--ntasks-per-node"], "1");
  EXPECT_FALSE(sbatch["--cpus-per-task"].empty());
  std::smatch match;
  const std::string signal = sbatch["--signal"];
  ASSERT_TRUE(std::regex_match(signal, match, std::regex(R"((?:B:)?(TERM|15)@(\d+))")))
      << "--signal=TERM@SECONDS lets the workers stop cleanly before the time limit, not "
      << signal;
  EXPECT_GE(std::stoi(match[2]), test::worker_shutdown_bound_s());
  EXPECT_NE(srun.find("--ntasks-per-node=1"), std::string::npos) << srun;
}

}  // namespace
}  // namespace tessera
