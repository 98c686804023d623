#include "server/api/asset_store.hpp"
#include "common/protocol/asset_digest.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <openssl/evp.h>

#include "server/farm/ids.hpp"

namespace tessera {

struct AssetStore::Upload::Digest {
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  ~Digest() { EVP_MD_CTX_free(context); }
};

AssetStore::AssetStore(std::filesystem::path dir, std::uint64_t max_bytes)
    : dir_(std::move(dir)), incoming_(dir_ / "incoming"), max_bytes_(max_bytes) {
  std::filesystem::create_directories(incoming_);
  for (const auto& entry : std::filesystem::directory_iterator(incoming_)) {
    std::error_code ignored;
    std::filesystem::remove(entry.path(), ignored);
  }
}

std::optional<std::filesystem::path> AssetStore::find(std::string_view sha256) const {
  if (!protocol::is_sha256_hex(sha256)) return std::nullopt;
  std::filesystem::path path = dir_ / std::string(sha256);
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return std::nullopt;
  return path;
}

std::optional<std::filesystem::path> AssetStore::reference(std::string_view sha256) {
  std::lock_guard lock(mutex_);
  auto path = find(sha256);
  std::error_code ignored;
  if (path)
    std::filesystem::last_write_time(*path, std::filesystem::file_time_type::clock::now(), ignored);
  return path;
}

std::size_t AssetStore::collect(std::chrono::seconds retention,
                                const std::set<std::string>& in_use) {
  std::lock_guard lock(mutex_);
  const auto cutoff = std::filesystem::file_time_type::clock::now() - retention;
  std::size_t removed = 0;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir_, error)) {
    const std::string name = entry.path().filename().string();
    if (!protocol::is_sha256_hex(name) || in_use.contains(name) || !entry.is_regular_file(error))
      continue;
    if (entry.last_write_time(error) > cutoff || error) continue;
    if (std::filesystem::remove(entry.path(), error)) ++removed;
  }
  return removed;
}

std::unique_ptr<AssetStore::Upload> AssetStore::begin_upload() {
  std::unique_ptr<Upload> upload(new Upload());
  upload->path_ = incoming_ / random_hex(32);
  upload->fd_ = ::open(upload->path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0640);
  if (upload->fd_ < 0)
    throw std::runtime_error("cannot create " + upload->path_.string() + ": " +
                             std::strerror(errno));
  upload->digest_ = std::make_unique<Upload::Digest>();
  if (!upload->digest_->context ||
      EVP_DigestInit_ex(upload->digest_->context, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("OpenSSL could not start a SHA-256");
  return upload;
}

AssetStore::Upload::~Upload() {
  if (fd_ >= 0) ::close(fd_);
  std::error_code ignored;
  if (!path_.empty()) std::filesystem::remove(path_, ignored);
}

bool AssetStore::Upload::write(std::string_view bytes) {
  if (EVP_DigestUpdate(digest_->context, bytes.data(), bytes.size()) != 1) return false;
  while (!bytes.empty()) {
    const ssize_t written = ::write(fd_, bytes.data(), bytes.size());
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return false;
    bytes.remove_prefix(static_cast<std::size_t>(written));
    size_ += static_cast<std::uint64_t>(written);
  }
  return true;
}

AssetStore::Committed AssetStore::commit(Upload& upload, std::string_view sha256,
                                         std::string* actual) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned length = 0;
  if (EVP_DigestFinal_ex(upload.digest_->context, digest.data(), &length) != 1)
    return Committed::failed;
  const std::string text = to_hex(digest.data(), length);
  if (actual) *actual = text;
  if (text != sha256) return Committed::wrong_digest;
  // On the disk before it is named, so that a crash never leaves a named asset whose
  // bytes are not all there.
  if (::fsync(upload.fd_) != 0) return Committed::failed;
  const std::filesystem::path target = dir_ / std::string(sha256);
  if (::link(upload.path_.c_str(), target.c_str()) != 0)
    return errno == EEXIST ? Committed::already_held : Committed::failed;
  return Committed::added;
}

}  // namespace tessera
