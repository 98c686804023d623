#include "server/store.hpp"

#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstring>
#include <limits>
#include <map>
#include <stdexcept>
#include <system_error>

#include "common/image_io.hpp"

namespace tessera {
namespace {

// Tile pixels are stored as the float32 bytes of this machine; the farm is x86-64 only,
// and this keeps a stored tile readable by anything that knows "float32 little-endian".
static_assert(std::endian::native == std::endian::little);
static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559);

constexpr int schema_version = 5;

constexpr const char* schema_sql = R"sql(
CREATE TABLE scenes (
  digest TEXT PRIMARY KEY,
  json TEXT NOT NULL
);
CREATE TABLE jobs (
  id TEXT PRIMARY KEY,
  name TEXT NOT NULL,
  priority INTEGER NOT NULL,
  state TEXT NOT NULL,
  width INTEGER NOT NULL,
  height INTEGER NOT NULL,
  tile_size INTEGER NOT NULL,
  scene_digest TEXT NOT NULL REFERENCES scenes(digest),
  created_at_ms INTEGER NOT NULL,
  started_at_ms INTEGER NOT NULL DEFAULT 0,
  finished_at_ms INTEGER NOT NULL DEFAULT 0,
  error TEXT NOT NULL DEFAULT '',
  rays INTEGER NOT NULL DEFAULT 0,
  output_transfer TEXT NOT NULL DEFAULT 'srgb'  -- the scene's render.output_transfer
);
CREATE INDEX jobs_by_scene ON jobs(scene_digest);
CREATE TABLE workers (
  id TEXT PRIMARY KEY,
  name TEXT NOT NULL,
  host TEXT NOT NULL,
  threads INTEGER NOT NULL,
  state TEXT NOT NULL,
  tiles_rendered INTEGER NOT NULL DEFAULT 0,
  last_seen_ms INTEGER NOT NULL
);
)sql";

// What is kept of tiles (schema version 4): a row per live lease, per accepted upload and
// per failed tile, and the pixels of each job's uploads appended to a file of its own
// (pixel_path()). Version 3 kept a row per tile, written when the tile was submitted,
// leased and delivered, with a row of pixels each: at 8-pixel tiles that per-tile work was
// most of the coordinator's, and took the CPU that the workers on the same machine needed.
// Pixels left SQLite too: storing 200 KB as a blob cost about 1.2 ms here (2.2 ms with the
// checkpoint that copies it again), one write of the same bytes to a file 0.03 ms. Tile
// index lists are int32 and rays int64, little-endian, packed in blobs.
constexpr const char* tile_tables_sql = R"sql(
CREATE TABLE leases (
  id TEXT PRIMARY KEY,
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  worker_id TEXT NOT NULL,
  tiles BLOB NOT NULL
);
CREATE INDEX leases_by_job ON leases(job_id);
CREATE TABLE results (
  id INTEGER PRIMARY KEY,
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  lease_id TEXT NOT NULL,
  worker_id TEXT NOT NULL,
  tiles BLOB NOT NULL,
  rays BLOB NOT NULL,
  pixels_at INTEGER NOT NULL,  -- where its pixels start in the job's pixel file, in bytes
  pixel_bytes INTEGER NOT NULL
);
CREATE INDEX results_by_job ON results(job_id);
CREATE TABLE tile_failures (
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  tile_index INTEGER NOT NULL,
  attempts INTEGER NOT NULL,
  last_error TEXT NOT NULL,
  PRIMARY KEY (job_id, tile_index)
);
)sql";

// The tile rows of versions 1 to 3, for upgrading them: version 3 kept a done tile's pixels
// in a table of their own, pointed to by the tile row.
constexpr const char* v3_pixels_table_sql = R"sql(
CREATE TABLE tile_pixels (
  id INTEGER PRIMARY KEY,
  pixels BLOB NOT NULL
);
)sql";

// The SQLite page cache, at most (a negative cache_size is KiB). The tiles being handed
// out and delivered stay in it; the default 2 MiB read them back from the file again and
// again on a big job.
constexpr int cache_kib = 32 * 1024;

// Creates the directories before the database file is opened in them.
std::filesystem::path prepare_data_dir(const std::filesystem::path& data_dir) {
  std::filesystem::create_directories(data_dir / "images");
  std::filesystem::create_directories(data_dir / "pixels");
  return data_dir / "tessera.db";
}

// Deletes the files of `dir` named JOB`extension` whose job is not kept, and those whose
// name starts with a dot: write_image's temporary files, one left over being a crashed write.
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

template <typename T>
std::span<const std::byte> bytes_of(const std::vector<T>& values) {
  return std::as_bytes(std::span(values));
}

// Unpacks a blob of packed little-endian values; trailing bytes short of a whole value are
// dropped (load()'s caller then finds the counts do not match).
template <typename T>
std::vector<T> unpack(std::span<const std::byte> bytes) {
  std::vector<T> values(bytes.size() / sizeof(T));
  if (!values.empty()) std::memcpy(values.data(), bytes.data(), values.size() * sizeof(T));
  return values;
}

}  // namespace

Store::Store(const std::filesystem::path& data_dir)
    : data_dir_(data_dir), db_(prepare_data_dir(data_dir)) {
  // WAL lets readers (the sqlite3 tool, backups) work beside the writer; NORMAL sync in
  // WAL mode never corrupts, it may only lose the last commits on power loss.
  db_.exec("PRAGMA journal_mode=WAL");
  db_.exec("PRAGMA synchronous=NORMAL");
  db_.exec("PRAGMA foreign_keys=ON");
  db_.exec("PRAGMA cache_size=-" + std::to_string(cache_kib));
  create_schema();
  db_.checkpoint_in_background();
}

void Store::create_schema() {
  const int version = std::stoi(db_.query_text("PRAGMA user_version"));
  if (version == schema_version) return;
  if (version < 0 || version > schema_version)
    throw std::runtime_error("store: " + (data_dir_ / "tessera.db").string() +
                             " has schema version " + std::to_string(version) +
                             "; this build knows version " + std::to_string(schema_version));
  Transaction tx(db_);
  if (version == 0) {
    db_.exec(schema_sql);
    db_.exec(tile_tables_sql);
  }
  if (version == 1)  // before tiles remembered why they failed
    db_.exec("ALTER TABLE tiles ADD COLUMN last_error TEXT NOT NULL DEFAULT ''");
  if (version == 1 || version == 2) {  // before pixels had a table of their own
    db_.exec("ALTER TABLE tiles ADD COLUMN pixels_id INTEGER");
    db_.exec(v3_pixels_table_sql);
    // The tile rows' own rowids are unique, so they serve as the new keys.
    db_.exec(
        "INSERT INTO tile_pixels (id, pixels) SELECT rowid, pixels FROM tiles WHERE pixels IS NOT "
        "NULL");
    db_.exec("UPDATE tiles SET pixels_id = rowid WHERE pixels IS NOT NULL");
    db_.exec("ALTER TABLE tiles DROP COLUMN pixels");
  }
  if (version >= 1 && version <= 3) migrate_tile_rows();
  if (version >= 1 && version <= 4) {  // before jobs kept their scene's output transfer
    db_.exec("ALTER TABLE jobs ADD COLUMN output_transfer TEXT NOT NULL DEFAULT 'srgb'");
    // Read once, here, from each job's scene (SQLite's JSON functions are built in).
    db_.exec(
        "UPDATE jobs SET output_transfer = 'linear' WHERE (SELECT json_extract(s.json, "
        "'$.render.output_transfer') FROM scenes s WHERE s.digest = jobs.scene_digest) = "
        "'linear'");
  }
  db_.exec("PRAGMA user_version=" + std::to_string(schema_version));
  tx.commit();
}

void Store::migrate_tile_rows() {
  db_.exec(tile_tables_sql);
  db_.exec(
      "INSERT INTO tile_failures (job_id, tile_index, attempts, last_error) "
      "SELECT job_id, tile_index, attempts, last_error FROM tiles "
      "WHERE attempts > 0 OR last_error != ''");
  // A done tile without its pixels renders again, and its rays are no longer the job's.
  db_.exec(
      "UPDATE jobs SET rays = max(0, rays - (SELECT ifnull(sum(t.rays), 0) FROM tiles t "
      "WHERE t.job_id = jobs.id AND t.state = 'done' AND t.pixels_id IS NULL))");
  {  // each done tile becomes a result of its own
    auto s = db_.statement(
        "SELECT t.job_id, t.tile_index, t.rays, t.result_lease_id, t.worker_id, p.pixels "
        "FROM tiles t JOIN tile_pixels p ON p.id = t.pixels_id WHERE t.state = 'done'");
    while (s->step()) {
      ResultRow result;
      result.job_id = s->column_text(0);
      result.tiles = {s->column_int(1)};
      result.rays = {static_cast<std::uint64_t>(s->column_int64(2))};
      result.lease_id = s->column_text(3);
      result.worker_id = s->column_text(4);
      const std::span<const std::byte> pixels = s->column_blob(5);
      insert_result_at(result, append_pixels(result.job_id, {&pixels, 1}), pixels.size());
    }
  }
  {  // the live leases, one row each
    std::map<std::string, LeaseRow> leases;
    auto s = db_.statement(
        "SELECT lease_id, job_id, worker_id, tile_index FROM tiles "
        "WHERE state = 'leased' AND lease_id != ''");
    while (s->step()) {
      LeaseRow& lease = leases[s->column_text(0)];
      lease.job_id = s->column_text(1);
      lease.worker_id = s->column_text(2);
      lease.tiles.push_back(s->column_int(3));
    }
    for (auto& [id, lease] : leases) {
      lease.id = id;
      put_lease(lease);
    }
  }
  db_.exec("DROP TRIGGER IF EXISTS tile_pixels_replaced");
  db_.exec("DROP TRIGGER IF EXISTS tile_pixels_deleted");
  db_.exec("DROP TABLE tiles");
  db_.exec("DROP TABLE tile_pixels");
}

std::filesystem::path Store::pixel_path(const std::string& job_id) const {
  return data_dir_ / "pixels" / (job_id + ".f32");
}

std::filesystem::path Store::image_path(const std::string& job_id) const {
  return data_dir_ / "images" / (job_id + ".exr");
}

StoredState Store::load() {
  StoredState state;
  Transaction tx(db_);  // one snapshot for every table
  {
    auto s = db_.statement(
        "SELECT id, name, priority, state, width, height, tile_size, scene_digest, "
        "created_at_ms, started_at_ms, finished_at_ms, error, rays, output_transfer FROM jobs");
    while (s->step()) {
      JobRow& job = state.jobs.emplace_back();
      job.id = s->column_text(0);
      job.name = s->column_text(1);
      job.priority = s->column_int(2);
      job.state = s->column_text(3);
      job.width = s->column_int(4);
      job.height = s->column_int(5);
      job.tile_size = s->column_int(6);
      job.scene_digest = s->column_text(7);
      job.created_at_ms = s->column_int64(8);
      job.started_at_ms = s->column_int64(9);
      job.finished_at_ms = s->column_int64(10);
      job.error = s->column_text(11);
      job.rays = static_cast<std::uint64_t>(s->column_int64(12));
      job.output_transfer = s->column_text(13);
    }
  }
  {
    auto s = db_.statement("SELECT id, job_id, worker_id, tiles FROM leases");
    while (s->step()) {
      LeaseRow& lease = state.leases.emplace_back();
      lease.id = s->column_text(0);
      lease.job_id = s->column_text(1);
      lease.worker_id = s->column_text(2);
      lease.tiles = unpack<int>(s->column_blob(3));
    }
  }
  {
    // What each job's pixel file holds: a result whose pixels it does not hold whole (the
    // machine lost power before they reached the disk) is reported with the bytes there are.
    std::map<std::string, std::int64_t> file_bytes;
    const auto bytes_in_file = [&](const std::string& job_id) {
      auto it = file_bytes.find(job_id);
      if (it == file_bytes.end()) {
        std::error_code error;
        const auto size = std::filesystem::file_size(pixel_path(job_id), error);
        it = file_bytes.emplace(job_id, error ? 0 : static_cast<std::int64_t>(size)).first;
      }
      return it->second;
    };
    auto s = db_.statement(
        "SELECT id, job_id, lease_id, worker_id, tiles, rays, pixels_at, pixel_bytes FROM results "
        "ORDER BY id");
    while (s->step()) {
      ResultRow& result = state.results.emplace_back();
      result.id = s->column_int64(0);
      result.job_id = s->column_text(1);
      result.lease_id = s->column_text(2);
      result.worker_id = s->column_text(3);
      result.tiles = unpack<int>(s->column_blob(4));
      result.rays = unpack<std::uint64_t>(s->column_blob(5));
      const std::int64_t at = s->column_int64(6);
      const std::int64_t stored = std::max<std::int64_t>(s->column_int64(7), 0);
      // A row that says its pixels start before the file does is no better than one whose
      // pixels the file lacks: both are reported as short, and forgotten.
      result.pixel_bytes =
          at < 0 ? 0 : std::clamp<std::int64_t>(bytes_in_file(result.job_id) - at, 0, stored);
    }
  }
  {
    auto s = db_.statement("SELECT job_id, tile_index, attempts, last_error FROM tile_failures");
    while (s->step()) {
      TileFailureRow& failure = state.failures.emplace_back();
      failure.job_id = s->column_text(0);
      failure.tile_index = s->column_int(1);
      failure.attempts = s->column_int(2);
      failure.last_error = s->column_text(3);
    }
  }
  {
    auto s = db_.statement(
        "SELECT id, name, host, threads, state, tiles_rendered, last_seen_ms FROM workers");
    while (s->step()) {
      WorkerRow& worker = state.workers.emplace_back();
      worker.id = s->column_text(0);
      worker.name = s->column_text(1);
      worker.host = s->column_text(2);
      worker.threads = s->column_int(3);
      worker.state = s->column_text(4);
      worker.tiles_rendered = static_cast<std::uint64_t>(s->column_int64(5));
      worker.last_seen_ms = s->column_int64(6);
    }
  }
  tx.commit();
  return state;
}

void Store::insert_job(const JobRow& job, const std::string& scene_json) {
  Transaction tx(db_);
  db_.statement("INSERT OR IGNORE INTO scenes (digest, json) VALUES (?, ?)")
      ->bind(1, job.scene_digest)
      .bind(2, scene_json)
      .run();
  db_.statement(
         "INSERT INTO jobs (id, name, priority, state, width, height, tile_size, scene_digest, "
         "created_at_ms, started_at_ms, finished_at_ms, error, rays, output_transfer) "
         "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      ->bind(1, job.id)
      .bind(2, job.name)
      .bind(3, job.priority)
      .bind(4, job.state)
      .bind(5, job.width)
      .bind(6, job.height)
      .bind(7, job.tile_size)
      .bind(8, job.scene_digest)
      .bind(9, job.created_at_ms)
      .bind(10, job.started_at_ms)
      .bind(11, job.finished_at_ms)
      .bind(12, job.error)
      .bind(13, static_cast<std::int64_t>(job.rays))
      .bind(14, job.output_transfer)
      .run();
  tx.commit();
}

void Store::update_job(const JobRow& job) {
  db_.statement(
         "UPDATE jobs SET name = ?, priority = ?, state = ?, started_at_ms = ?, "
         "finished_at_ms = ?, error = ?, rays = ? WHERE id = ?")
      ->bind(1, job.name)
      .bind(2, job.priority)
      .bind(3, job.state)
      .bind(4, job.started_at_ms)
      .bind(5, job.finished_at_ms)
      .bind(6, job.error)
      .bind(7, static_cast<std::int64_t>(job.rays))
      .bind(8, job.id)
      .run();
}

void Store::delete_job(const std::string& job_id) {
  Transaction tx(db_);
  std::string digest;
  {
    auto s = db_.statement("SELECT scene_digest FROM jobs WHERE id = ?");
    s->bind(1, job_id);
    if (s->step()) digest = s->column_text(0);
  }
  // Explicitly, though the foreign keys cascade: each by its own index.
  db_.statement("DELETE FROM leases WHERE job_id = ?")->bind(1, job_id).run();
  db_.statement("DELETE FROM results WHERE job_id = ?")->bind(1, job_id).run();
  db_.statement("DELETE FROM tile_failures WHERE job_id = ?")->bind(1, job_id).run();
  db_.statement("DELETE FROM jobs WHERE id = ?")->bind(1, job_id).run();
  db_.statement(
         "DELETE FROM scenes WHERE digest = ?1 "
         "AND NOT EXISTS (SELECT 1 FROM jobs WHERE scene_digest = ?1)")
      ->bind(1, digest)
      .run();
  tx.commit();
  // After the commit: a file left behind by a failure here is pruned on the next start,
  // while a row without its image would be a completed job that cannot be served.
  remove_image(job_id);
  std::error_code ignored;
  std::filesystem::remove(pixel_path(job_id), ignored);
}

std::optional<std::string> Store::scene_json(const std::string& digest) {
  auto s = db_.statement("SELECT json FROM scenes WHERE digest = ?");
  s->bind(1, digest);
  if (!s->step()) return std::nullopt;
  return s->column_text(0);
}

void Store::put_lease(const LeaseRow& lease) {
  db_.statement(
         "INSERT INTO leases (id, job_id, worker_id, tiles) VALUES (?, ?, ?, ?) "
         "ON CONFLICT (id) DO UPDATE SET worker_id = excluded.worker_id, tiles = excluded.tiles")
      ->bind(1, lease.id)
      .bind(2, lease.job_id)
      .bind(3, lease.worker_id)
      .bind_blob(4, bytes_of(lease.tiles))
      .run();
}

void Store::delete_lease(const std::string& lease_id) {
  db_.statement("DELETE FROM leases WHERE id = ?")->bind(1, lease_id).run();
}

std::int64_t Store::insert_result(const ResultRow& result,
                                  std::span<const std::span<const float>> pixels) {
  std::vector<std::span<const std::byte>> bytes;
  bytes.reserve(pixels.size());
  std::size_t total = 0;
  for (const std::span<const float> tile : pixels) {
    bytes.push_back(std::as_bytes(tile));
    total += tile.size_bytes();
  }
  return insert_result_at(result, append_pixels(result.job_id, bytes), total);
}

std::int64_t Store::append_pixels(const std::string& job_id,
                                  std::span<const std::span<const std::byte>> parts) {
  const std::filesystem::path path = pixel_path(job_id);
  const auto fail = [&](const char* what, int error) -> std::runtime_error {
    // SQLite says "database or disk is full" for its own; the same words for ours.
    const std::string why = error == ENOSPC || error == EDQUOT
                                ? "the disk is full (" + std::string(std::strerror(error)) + ")"
                                : std::string(std::strerror(error));
    return std::runtime_error("store: cannot " + std::string(what) + " " + path.string() + ": " +
                              why);
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

std::int64_t Store::insert_result_at(const ResultRow& result, std::int64_t pixels_at,
                                     std::size_t pixel_bytes) {
  auto s = db_.statement(
      "INSERT INTO results (job_id, lease_id, worker_id, tiles, rays, pixels_at, pixel_bytes) "
      "VALUES (?, ?, ?, ?, ?, ?, ?) RETURNING id");
  s->bind(1, result.job_id)
      .bind(2, result.lease_id)
      .bind(3, result.worker_id)
      .bind_blob(4, bytes_of(result.tiles))
      .bind_blob(5, bytes_of(result.rays))
      .bind(6, pixels_at)
      .bind(7, static_cast<std::int64_t>(pixel_bytes));
  if (!s->step()) throw std::runtime_error("store: INSERT INTO results returned no id");
  const std::int64_t id = s->column_int64(0);
  s->run();  // to the end, so that the insert is complete
  return id;
}

void Store::delete_result(std::int64_t result_id) {
  db_.statement("DELETE FROM results WHERE id = ?")->bind(1, result_id).run();
}

void Store::put_tile_failure(const TileFailureRow& failure) {
  db_.statement(
         "INSERT INTO tile_failures (job_id, tile_index, attempts, last_error) VALUES (?, ?, ?, ?) "
         "ON CONFLICT (job_id, tile_index) DO UPDATE SET attempts = excluded.attempts, "
         "last_error = excluded.last_error")
      ->bind(1, failure.job_id)
      .bind(2, failure.tile_index)
      .bind(3, failure.attempts)
      .bind(4, failure.last_error)
      .run();
}

void Store::for_each_tile_pixels(
    const std::string& job_id, const std::function<std::size_t(int tile_index)>& floats_of,
    const std::function<void(int tile_index, std::span<const float>)>& visit) {
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
    if (fd < 0 && (fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC)) < 0)
      throw std::runtime_error("store: cannot open " + path.string() + ": " + std::strerror(errno));
    floats.resize(bytes / sizeof(float));
    std::size_t got = 0;
    while (got < floats.size() * sizeof(float)) {
      const ssize_t n =
          ::pread(fd, reinterpret_cast<char*>(floats.data()) + got,
                  floats.size() * sizeof(float) - got, at + static_cast<std::int64_t>(got));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0)
        throw std::runtime_error("store: cannot read " + path.string() + ": " +
                                 std::strerror(errno));
      if (n == 0) break;  // the file ends early: the check below names the tile
      got += static_cast<std::size_t>(n);
    }
    std::size_t offset = 0;
    for (const int index : tiles) {
      const std::size_t size = floats_of(index);
      if ((offset + size) * sizeof(float) > got)
        throw std::runtime_error("store: the stored pixels of job " + job_id + " end before tile " +
                                 std::to_string(index));
      visit(index, std::span<const float>(floats).subspan(offset, size));
      offset += size;
    }
  }
}

void Store::upsert_worker(const WorkerRow& worker) {
  db_.statement(
         "INSERT INTO workers (id, name, host, threads, state, tiles_rendered, last_seen_ms) "
         "VALUES (?, ?, ?, ?, ?, ?, ?) ON CONFLICT (id) DO UPDATE SET name = excluded.name, "
         "host = excluded.host, threads = excluded.threads, state = excluded.state, "
         "tiles_rendered = excluded.tiles_rendered, last_seen_ms = excluded.last_seen_ms")
      ->bind(1, worker.id)
      .bind(2, worker.name)
      .bind(3, worker.host)
      .bind(4, worker.threads)
      .bind(5, worker.state)
      .bind(6, static_cast<std::int64_t>(worker.tiles_rendered))
      .bind(7, worker.last_seen_ms)
      .run();
}

void Store::update_worker_seen(const std::string& worker_id, std::int64_t last_seen_ms) {
  db_.statement("UPDATE workers SET last_seen_ms = ? WHERE id = ?")
      ->bind(1, last_seen_ms)
      .bind(2, worker_id)
      .run();
}

void Store::write_image(const std::string& job_id, const Image& image) {
  tessera::write_image(image, image_path(job_id), OutputTransfer::linear);
}

void Store::remove_image(const std::string& job_id) {
  std::error_code ignored;
  std::filesystem::remove(image_path(job_id), ignored);
}

bool Store::has_image(const std::string& job_id) const {
  std::error_code ignored;
  return std::filesystem::is_regular_file(image_path(job_id), ignored);
}

void Store::prune_images(const std::function<bool(const std::string& job_id)>& keep) {
  prune_files(data_dir_ / "images", ".exr", keep);
}

void Store::prune_pixels(const std::function<bool(const std::string& job_id)>& keep) {
  prune_files(data_dir_ / "pixels", ".f32", keep);
}

}  // namespace tessera
