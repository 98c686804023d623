#include "worker/asset_cache.hpp"

#include <unistd.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

#include "common/net/file_digest.hpp"

namespace tessera {
AssetCache::AssetCache(std::filesystem::path dir, std::uint64_t max_bytes)
    : dir_(std::move(dir)), max_bytes_(max_bytes) {
  std::filesystem::create_directories(dir_);
}

std::filesystem::path AssetCache::get(const std::string& sha256, const Fetch& fetch) {
  const std::filesystem::path path = dir_ / sha256;
  std::error_code error;
  if (std::filesystem::is_regular_file(path, error)) {
    if (file_sha256(path) == sha256) {
      // Its time of last use, for trim().
      std::filesystem::last_write_time(path, std::filesystem::file_time_type::clock::now(), error);
      return path;
    }
    std::filesystem::remove(path, error);  // corrupt: fetched again below
  }
  // Written beside its name as it arrives, and renamed once checked, so that another
  // worker sharing the folder never sees a part of it.
  const std::filesystem::path part = dir_ / (sha256 + ".part-" + std::to_string(::getpid()) + "-" +
                                             std::to_string(std::random_device{}()));
  try {
    fetch(part);
    const std::string actual = file_sha256(part);
    if (actual != sha256)
      throw std::runtime_error("asset sha256:" + sha256 + " arrived with the digest sha256:" +
                               (actual.empty() ? std::string("(unreadable)") : actual));
  } catch (...) {
    std::filesystem::remove(part, error);
    throw;
  }
  std::filesystem::rename(part, path);
  return path;
}

void AssetCache::trim(const std::set<std::string>& keep) {
  struct Entry {
    std::filesystem::path path;
    std::uint64_t size;
    std::filesystem::file_time_type used;
  };
  std::vector<Entry> entries;
  std::uint64_t total = 0;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir_, error)) {
    if (!entry.is_regular_file(error)) continue;
    const std::uint64_t size = entry.file_size(error);
    total += size;
    entries.push_back({entry.path(), size, entry.last_write_time(error)});
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.used < b.used; });
  for (const Entry& entry : entries) {
    if (total <= max_bytes_) break;
    if (keep.contains(entry.path.filename().string())) continue;
    if (std::filesystem::remove(entry.path, error)) total -= entry.size;
  }
}

}  // namespace tessera
