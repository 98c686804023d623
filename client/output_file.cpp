#include "client/output_file.hpp"

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

#include "client/command_failure.hpp"

namespace tessera {

OutputFile::OutputFile(std::filesystem::path path)
    : path_(std::move(path)), part_(path_.string() + ".part") {
  out_.open(part_, std::ios::binary | std::ios::trunc);
  if (!out_) fail(kExitUsage, "cannot write " + path_.string() + ": " + std::strerror(errno));
}

OutputFile::~OutputFile() {
  if (kept_) return;
  out_.close();
  std::error_code ignored;
  std::filesystem::remove(part_, ignored);
}

void OutputFile::commit(std::string_view bytes) {
  out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out_.close();
  if (!out_) fail(kExitJobFailed, "cannot write " + path_.string() + ": " + std::strerror(errno));
  std::error_code error;
  std::filesystem::rename(part_, path_, error);
  if (error) fail(kExitJobFailed, "cannot write " + path_.string() + ": " + error.message());
  kept_ = true;
}

}  // namespace tessera
