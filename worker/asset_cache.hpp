// A worker's assets (mesh files and the files they name), kept on its disk by digest so that
// each is downloaded once and shared by every job that names it. Bounded in size: the least
// recently used go first. An entry whose bytes no longer have its digest is fetched again.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <set>
#include <string>

namespace tessera {

class AssetCache {
 public:
  AssetCache(std::filesystem::path dir, std::uint64_t max_bytes);

  // The file of the asset `sha256` (64 hex digits): the cached one when its bytes have
  // that digest, else what `fetch` writes to the file it is given, checked and moved into
  // place. Throws std::runtime_error for bytes of another digest (and keeps none of them).
  using Fetch = std::function<void(const std::filesystem::path& into)>;
  std::filesystem::path get(const std::string& sha256, const Fetch& fetch);

  // Removes the least recently used entries, but none of `keep`, until the rest fit.
  void trim(const std::set<std::string>& keep);

  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::uint64_t max_bytes_;
};

}  // namespace tessera
