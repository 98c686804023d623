#include "server/farm/prune_files.hpp"

namespace tessera {

void prune_files(const std::filesystem::path& dir, const char* extension,
                 const std::function<bool(const std::string& job_id)>& keep) {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::filesystem::path& path = entry.path();
    if (path.extension() != extension) continue;
    const std::string stem = path.stem().string();
    if (stem.starts_with(".") || !keep(stem)) {
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
    }
  }
}

}  // namespace tessera
