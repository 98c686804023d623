// A file the CLI downloads into, written whole or not at all.
#pragma once

#include <filesystem>
#include <fstream>
#include <string_view>

namespace tessera {

// A ".part" file beside `path`, opened at once so that a path that cannot be written costs
// no download, renamed into place once complete, and removed however the command ends
// otherwise: nothing half-written is left behind.
class OutputFile {
 public:
  // Fails (client/command_failure.hpp) with kExitUsage when `path` cannot be written.
  explicit OutputFile(std::filesystem::path path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Writes `bytes` and renames the file into place; fails with kExitJobFailed when either
  // does not work out.
  void commit(std::string_view bytes);

 private:
  std::filesystem::path path_;
  std::filesystem::path part_;
  std::ofstream out_;
  bool kept_ = false;
};

}  // namespace tessera
