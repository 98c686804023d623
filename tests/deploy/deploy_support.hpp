// Shared by the tests of deploy/: reading the repository's files, and the figures the
// deployment files must agree with, taken from the sources they describe so that a change
// there fails the tests instead of silently making the manifests wrong.
#pragma once

#include <fnmatch.h>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace tessera::test {

namespace deploy_fs = std::filesystem;

inline deploy_fs::path source_path(const std::string& relative) {
  return deploy_fs::path(TESSERA_SOURCE_DIR) / relative;
}

inline std::string read_source(const std::string& relative) {
  std::ifstream in(source_path(relative), std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + relative);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline std::vector<std::string> source_lines(const std::string& relative) {
  std::istringstream in(read_source(relative));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The first capture of `pattern` in the file, or nothing.
inline std::optional<std::string> find_in_source(const std::string& relative,
                                                 const std::string& pattern) {
  const std::string text = read_source(relative);
  std::smatch match;
  if (!std::regex_search(text, match, std::regex(pattern))) return std::nullopt;
  return match[1].str();
}

// How long a tessera-worker may take to exit after SIGTERM, from worker/worker_daemon.cpp:
// each thread finishes its tile, then the worker's upload senders make one attempt each, side
// by side (kUploadTimeout), and it releases the rest of its lease (client_'s timeout: claim_wait_s
// plus a margin). Every grace period in deploy/ must cover this, plus some time for the tile.
inline int worker_shutdown_bound_s() {
  const auto upload = find_in_source("worker/worker_daemon.cpp",
                                     R"(kUploadTimeout\s*=\s*std::chrono::seconds\((\d+)\))");
  const auto margin = find_in_source("worker/worker_daemon.cpp",
                                     R"(\(options_\.claim_wait_s\s*\+\s*(\d+)\)\s*\*\s*1000)");
  const auto claim_wait =
      find_in_source("worker/worker_daemon.hpp", R"(double claim_wait_s\s*=\s*(\d+))");
  if (!upload || !margin || !claim_wait)
    throw std::runtime_error(
        "worker/worker_daemon.{cpp,hpp} no longer show the upload timeout, the claim timeout "
        "or claim_wait_s where tests/deploy/deploy_support.hpp looks: work out again how long a "
        "worker takes to stop on SIGTERM, and update the grace periods in deploy/ and this test");
  return std::stoi(*upload) + std::stoi(*claim_wait) + std::stoi(*margin);
}

// "120s", "2m", "1m30s", "90" (seconds): Compose's and systemd's durations.
inline std::optional<int> duration_s(const std::string& text) {
  static const std::regex part(R"((\d+)\s*(h|min|m|s|sec)?)");
  int total = 0;
  std::size_t consumed = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), part); it != std::sregex_iterator();
       ++it) {
    const int n = std::stoi((*it)[1]);
    const std::string unit = (*it)[2];
    total += unit == "h" ? n * 3600 : (unit == "m" || unit == "min") ? n * 60 : n;
    consumed += static_cast<std::size_t>(it->length());
  }
  std::string compact;
  for (char c : text)
    if (c != ' ') compact += c;
  if (consumed == 0 || consumed < compact.size()) return std::nullopt;
  return total;
}

// The value after `flag` in an argument list ("--threads", "4"), or "--flag=value".
inline std::optional<std::string> flag_value(const std::vector<std::string>& args,
                                             const std::string& flag) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == flag && i + 1 < args.size()) return args[i + 1];
    if (args[i].rfind(flag + "=", 0) == 0) return args[i].substr(flag.size() + 1);
  }
  return std::nullopt;
}

// Flags that would put a token itself on a command line (the *-file forms are fine).
inline std::vector<std::string> token_flags_in(const std::vector<std::string>& args) {
  std::vector<std::string> found;
  for (const std::string& arg : args)
    for (const char* flag : {"--api-token", "--worker-token", "--token"})
      if (arg == flag || arg.rfind(std::string(flag) + "=", 0) == 0) found.push_back(arg);
  return found;
}

// The port of "HOST:PORT".
inline int port_of(const std::string& listen) {
  return std::stoi(listen.substr(listen.rfind(':') + 1));
}

// Whether the ignore file (a .gitignore, or with `docker` a .dockerignore) excludes
// `relative`, a path from the ignore file's directory. Enough of both syntaxes for the
// patterns used here: globs, a leading "/" anchoring, a trailing "/" for directories, a
// pattern matching a directory excluding what is under it. A .gitignore pattern without
// a "/" matches a name at any depth; a .dockerignore pattern always starts at the root.
inline bool ignored_by(const std::string& ignore_file, const std::string& relative,
                       bool docker = false) {
  std::vector<std::string> parts;  // relative's components
  std::stringstream split(relative);
  for (std::string part; std::getline(split, part, '/');) parts.push_back(part);
  for (std::string pattern : source_lines(ignore_file)) {
    if (pattern.empty() || pattern[0] == '#') continue;
    while (!pattern.empty() && pattern.back() == '/') pattern.pop_back();
    const bool anchored = docker || pattern.find('/') != std::string::npos;
    if (!pattern.empty() && pattern[0] == '/') pattern.erase(0, 1);
    if (pattern.rfind("**/", 0) == 0) {  // any depth, as an unanchored git pattern
      pattern.erase(0, 3);
      for (const std::string& part : parts)
        if (::fnmatch(pattern.c_str(), part.c_str(), 0) == 0) return true;
      continue;
    }
    std::string prefix;
    for (const std::string& part : parts) {  // relative itself or a directory above it
      prefix += (prefix.empty() ? "" : "/") + part;
      if (anchored ? ::fnmatch(pattern.c_str(), prefix.c_str(), FNM_PATHNAME) == 0
                   : ::fnmatch(pattern.c_str(), part.c_str(), 0) == 0)
        return true;
    }
  }
  return false;
}

}  // namespace tessera::test
