#include "server/farm/sqlite_store.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <map>
#include <stdexcept>
#include <system_error>

#include "server/farm/packed_blobs.hpp"
#include "server/farm/store_error.hpp"

namespace tessera {
namespace {

// Tile pixels are stored as the float32 bytes of this machine; the farm is x86-64 only,
// and this keeps a stored tile readable by anything that knows "float32 little-endian".
static_assert(std::endian::native == std::endian::little);
static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559);

// The SQLite page cache, at most (a negative cache_size is KiB). The tiles being handed
// out and delivered stay in it; the default 2 MiB read them back from the file again and
// again on a big job.
constexpr int cache_kib = 32 * 1024;

// Creates the directories before the database file is opened in them.
std::filesystem::path prepare_data_dir(const std::filesystem::path& data_dir) {
  std::error_code error;
  std::filesystem::create_directories(data_dir / "pixels", error);
  if (error)
    throw StoreError(fault_of_errno(error.value()), "store: cannot create " +
                                                        (data_dir / "pixels").string() + ": " +
                                                        errno_words(error.value()));
  return data_dir / "tessera.db";
}

// WAL lets readers (the sqlite3 tool, backups) work beside the writer; NORMAL sync in WAL
// mode never corrupts, it may only lose the last commits on power loss. Run on every
// connection the store opens, also one it opens again (SqliteDb::reopen).
std::vector<std::string> connection_setup() {
  return {"PRAGMA journal_mode=WAL", "PRAGMA synchronous=NORMAL", "PRAGMA foreign_keys=ON",
          "PRAGMA cache_size=-" + std::to_string(cache_kib)};
}

}  // namespace

SqliteStore::SqliteStore(const std::filesystem::path& data_dir)
    : data_dir_(data_dir), db_(prepare_data_dir(data_dir), connection_setup()) {
  create_schema();
  db_.checkpoint_in_background();
}

StoredState SqliteStore::load() {
  Transaction tx(db_);  // one snapshot for every table
  StoredState state{job_rows(), lease_rows(), result_rows(), failure_rows(), worker_rows()};
  tx.commit();
  return state;
}

void SqliteStore::atomically(const std::function<void()>& writes) {
  Transaction tx(db_);
  writes();
  tx.commit();
}

std::vector<JobRow> SqliteStore::job_rows() {
  std::vector<JobRow> rows;
  auto s = db_.statement(
      "SELECT id, name, priority, state, width, height, tile_size, scene_digest, "
      "created_at_ms, started_at_ms, finished_at_ms, error, rays, output_transfer, frames FROM "
      "jobs");
  while (s->step()) {
    JobRow& job = rows.emplace_back();
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
    job.frames = s->column_text(14);
  }
  return rows;
}

std::vector<LeaseRow> SqliteStore::lease_rows() {
  std::vector<LeaseRow> rows;
  auto s = db_.statement("SELECT id, job_id, worker_id, tiles FROM leases");
  while (s->step()) {
    LeaseRow& lease = rows.emplace_back();
    lease.id = s->column_text(0);
    lease.job_id = s->column_text(1);
    lease.worker_id = s->column_text(2);
    lease.tiles = unpack<int>(s->column_blob(3));
  }
  return rows;
}

std::vector<ResultRow> SqliteStore::result_rows() {
  std::vector<ResultRow> rows;
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
    ResultRow& result = rows.emplace_back();
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
  return rows;
}

std::vector<TileFailureRow> SqliteStore::failure_rows() {
  std::vector<TileFailureRow> rows;
  auto s = db_.statement("SELECT job_id, tile_index, attempts, last_error FROM tile_failures");
  while (s->step()) {
    TileFailureRow& failure = rows.emplace_back();
    failure.job_id = s->column_text(0);
    failure.tile_index = s->column_int(1);
    failure.attempts = s->column_int(2);
    failure.last_error = s->column_text(3);
  }
  return rows;
}

std::vector<WorkerRow> SqliteStore::worker_rows() {
  std::vector<WorkerRow> rows;
  auto s = db_.statement(
      "SELECT id, name, host, threads, state, tiles_rendered, last_seen_ms, secret_sha256, "
      "draining FROM workers");
  while (s->step()) {
    WorkerRow& worker = rows.emplace_back();
    worker.id = s->column_text(0);
    worker.name = s->column_text(1);
    worker.host = s->column_text(2);
    worker.threads = s->column_int(3);
    worker.state = s->column_text(4);
    worker.tiles_rendered = static_cast<std::uint64_t>(s->column_int64(5));
    worker.last_seen_ms = s->column_int64(6);
    worker.secret_sha256 = s->column_text(7);
    worker.draining = s->column_int(8) != 0;
  }
  return rows;
}

void SqliteStore::insert_job(const JobRow& job, const std::string& scene_json) {
  Transaction tx(db_);
  db_.statement("INSERT OR IGNORE INTO scenes (digest, json) VALUES (?, ?)")
      ->bind(1, job.scene_digest)
      .bind_view(2, scene_json)
      .run();
  db_.statement(
         "INSERT INTO jobs (id, name, priority, state, width, height, tile_size, scene_digest, "
         "created_at_ms, started_at_ms, finished_at_ms, error, rays, output_transfer, frames) "
         "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
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
      .bind(15, job.frames)
      .run();
  tx.commit();
}

void SqliteStore::update_job(const JobRow& job) {
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

void SqliteStore::delete_job(const std::string& job_id) {
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
  // while a row without its pixels would be results that cannot be read.
  std::error_code ignored;
  std::filesystem::remove(pixel_path(job_id), ignored);
}

std::optional<std::string> SqliteStore::scene_json(const std::string& digest) {
  auto s = db_.statement("SELECT json FROM scenes WHERE digest = ?");
  s->bind(1, digest);
  if (!s->step()) return std::nullopt;
  return s->column_text(0);
}

void SqliteStore::put_lease(const LeaseRow& lease) {
  db_.statement(
         "INSERT INTO leases (id, job_id, worker_id, tiles) VALUES (?, ?, ?, ?) "
         "ON CONFLICT (id) DO UPDATE SET worker_id = excluded.worker_id, tiles = excluded.tiles")
      ->bind(1, lease.id)
      .bind(2, lease.job_id)
      .bind(3, lease.worker_id)
      .bind_blob(4, bytes_of(lease.tiles))
      .run();
}

void SqliteStore::delete_lease(const std::string& lease_id) {
  db_.statement("DELETE FROM leases WHERE id = ?")->bind(1, lease_id).run();
}

std::int64_t SqliteStore::insert_result(const ResultRow& result,
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

std::int64_t SqliteStore::insert_result_at(const ResultRow& result, std::int64_t pixels_at,
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

void SqliteStore::delete_result(std::int64_t result_id) {
  db_.statement("DELETE FROM results WHERE id = ?")->bind(1, result_id).run();
}

void SqliteStore::put_tile_failure(const TileFailureRow& failure) {
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

void SqliteStore::delete_worker(const std::string& id) {
  db_.statement("DELETE FROM workers WHERE id = ?")->bind(1, id).run();
}

void SqliteStore::upsert_worker(const WorkerRow& worker) {
  db_.statement(
         "INSERT INTO workers (id, name, host, threads, state, tiles_rendered, last_seen_ms, "
         "secret_sha256, draining) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (id) DO "
         "UPDATE SET name = excluded.name, host = excluded.host, threads = excluded.threads, "
         "state = excluded.state, tiles_rendered = excluded.tiles_rendered, "
         "last_seen_ms = excluded.last_seen_ms, secret_sha256 = excluded.secret_sha256, "
         "draining = excluded.draining")
      ->bind(1, worker.id)
      .bind(2, worker.name)
      .bind(3, worker.host)
      .bind(4, worker.threads)
      .bind(5, worker.state)
      .bind(6, static_cast<std::int64_t>(worker.tiles_rendered))
      .bind(7, worker.last_seen_ms)
      .bind(8, worker.secret_sha256)
      .bind(9, static_cast<int>(worker.draining))
      .run();
}

void SqliteStore::update_worker_seen(const std::string& worker_id, std::int64_t last_seen_ms) {
  db_.statement("UPDATE workers SET last_seen_ms = ? WHERE id = ?")
      ->bind(1, last_seen_ms)
      .bind(2, worker_id)
      .run();
}

}  // namespace tessera
