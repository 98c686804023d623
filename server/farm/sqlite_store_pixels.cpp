// The SQLite store's pixel files: each job's accepted pixels appended to data_dir/pixels/JOB.f32,
// where its result rows point.
#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include "server/farm/packed_blobs.hpp"
#include "server/farm/prune_files.hpp"
#include "server/farm/sqlite_store.hpp"
#include "server/farm/store_error.hpp"

namespace tessera {

std::filesystem::path SqliteStore::pixel_path(const std::string& job_id) const {
  return data_dir_ / pixel_name(job_id);
}

std::string SqliteStore::pixel_name(const std::string& job_id) {
  return "pixels/" + job_id + ".f32";
}

std::int64_t SqliteStore::append_pixels(const std::string& job_id,
                                        std::span<const std::span<const std::byte>> parts) {
  const std::filesystem::path path = pixel_path(job_id);
  // Named within the data dir: the message reaches clients as the job's error, and the
  // server's paths are none of theirs.
  const auto fail = [&](const char* what, int error) {
    return StoreError(fault_of_errno(error), "store: cannot " + std::string(what) + " " +
                                                 pixel_name(job_id) + ": " + errno_words(error));
  };
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw fail("open", errno);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat status {};
  if (::fstat(fd, &status) != 0) throw fail("read the size of", errno);
  // Appended after whatever is there, also the bytes of a result whose transaction was
  // rolled back: nothing points to those.
  const std::int64_t start = status.st_size;
  std::int64_t at = start;
  std::vector<iovec> pending;
  for (const std::span<const std::byte> part : parts)
    if (!part.empty()) pending.push_back({const_cast<std::byte*>(part.data()), part.size()});
  std::size_t first = 0;
  while (first < pending.size()) {
    const int count = static_cast<int>(std::min<std::size_t>(pending.size() - first, IOV_MAX));
    const ssize_t written = ::pwritev(fd, &pending[first], count, at);
    if (written < 0) {
      if (errno == EINTR) continue;
      throw fail("write the pixels to", errno);
    }
    if (written == 0) throw fail("write the pixels to", ENOSPC);
    at += written;
    // Past what was written whole; into the part written in part.
    auto left = static_cast<std::size_t>(written);
    while (first < pending.size() && left >= pending[first].iov_len)
      left -= pending[first++].iov_len;
    if (left > 0) {
      pending[first].iov_base = static_cast<std::byte*>(pending[first].iov_base) + left;
      pending[first].iov_len -= left;
    }
  }
  return start;
}

void SqliteStore::for_each_tile_pixels(
    const std::string& job_id, const std::function<std::size_t(int tile_index)>& floats_of,
    const std::function<void(int tile_index, std::span<const float>)>& visit,
    const std::function<bool(int tile_index)>& wanted) {
  auto s = db_.statement(
      "SELECT tiles, pixels_at, pixel_bytes FROM results WHERE job_id = ? ORDER BY id");
  s->bind(1, job_id);
  const std::filesystem::path path = pixel_path(job_id);
  int fd = -1;
  struct Closer {
    int& fd;
    ~Closer() {
      if (fd >= 0) ::close(fd);
    }
  } closer{fd};
  std::vector<float> floats;
  while (s->step()) {
    const std::vector<int> tiles = unpack<int>(s->column_blob(0));
    const std::int64_t at = s->column_int64(1);
    const auto bytes = static_cast<std::size_t>(s->column_int64(2));
    if (wanted && std::none_of(tiles.begin(), tiles.end(), wanted)) continue;
    if (fd < 0 && (fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC)) < 0)
      throw StoreError(fault_of_errno(errno),
                       "store: cannot open " + pixel_name(job_id) + ": " + errno_words(errno));
    floats.resize(bytes / sizeof(float));
    std::size_t got = 0;
    while (got < floats.size() * sizeof(float)) {
      const ssize_t n =
          ::pread(fd, reinterpret_cast<char*>(floats.data()) + got,
                  floats.size() * sizeof(float) - got, at + static_cast<std::int64_t>(got));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0)
        throw StoreError(fault_of_errno(errno),
                         "store: cannot read " + pixel_name(job_id) + ": " + errno_words(errno));
      if (n == 0) break;  // the file ends early: the check below names the tile
      got += static_cast<std::size_t>(n);
    }
    std::size_t offset = 0;
    for (const int index : tiles) {
      const std::size_t size = floats_of(index);
      if ((offset + size) * sizeof(float) > got)
        throw std::runtime_error("store: the stored pixels of job " + job_id + " end before tile " +
                                 std::to_string(index));
      if (!wanted || wanted(index))
        visit(index, std::span<const float>(floats).subspan(offset, size));
      offset += size;
    }
  }
}

void SqliteStore::prune_pixels(const std::function<bool(const std::string& job_id)>& keep) {
  prune_files(data_dir_ / "pixels", ".f32", keep);
}

}  // namespace tessera
