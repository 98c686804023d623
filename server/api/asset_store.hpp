// The coordinator's assets: files (meshes, their MTL and .bin, textures) named by the
// SHA-256 of their bytes, under DATA_DIR/assets/. An upload streams into a file of its own
// under DATA_DIR/assets/incoming/ while its digest is computed, and becomes the asset only
// once the whole body has arrived and its digest is the one it was sent under; anything
// less (a wrong digest, a full disk, a dropped connection) leaves nothing behind.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>

namespace tessera {

class AssetStore {
 public:
  // Creates the folders, and empties incoming/ of uploads a crash cut short.
  AssetStore(std::filesystem::path dir, std::uint64_t max_bytes);

  // The file of the asset with this digest (64 lower-case hex digits), when held.
  std::optional<std::filesystem::path> find(std::string_view sha256) const;
  // find() for a job being submitted that names the asset: its time of last reference
  // becomes now, under the lock that collect() holds, so that an asset a submission found is
  // never then removed for being old.
  std::optional<std::filesystem::path> reference(std::string_view sha256);
  // Removes each asset last referenced (or stored) longer than `retention` ago, except those
  // in `in_use`; returns how many went.
  std::size_t collect(std::chrono::seconds retention, const std::set<std::string>& in_use);
  std::uint64_t max_bytes() const { return max_bytes_; }

  // One upload in progress. Not thread-safe: one writer at a time, which the session's
  // order of reads gives it. Its file is removed unless commit() took it.
  class Upload {
   public:
    ~Upload();
    // Appends bytes to the file; false when the disk refuses them (full, say).
    bool write(std::string_view bytes);
    std::uint64_t size() const { return size_; }

   private:
    friend class AssetStore;
    Upload() = default;
    std::filesystem::path path_;
    int fd_ = -1;
    std::uint64_t size_ = 0;
    struct Digest;
    std::unique_ptr<Digest> digest_;
  };

  // Throws std::runtime_error when no file can be made for it.
  std::unique_ptr<Upload> begin_upload();

  enum class Committed { added, already_held, wrong_digest, failed };
  // Makes the upload the asset `sha256` once its bytes have that digest: flushed to the
  // disk, then linked into place, so that two uploads of one digest at once both succeed
  // and one file results.
  Committed commit(Upload& upload, std::string_view sha256, std::string* actual = nullptr);

 private:
  std::filesystem::path dir_;
  std::filesystem::path incoming_;
  std::uint64_t max_bytes_;
  std::mutex mutex_;  // reference() against collect()
};

}  // namespace tessera
