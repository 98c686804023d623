#include "server/store.hpp"

#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>

#include "common/image_io.hpp"

namespace tessera {
namespace {

// Tile pixels are stored as the float32 bytes of this machine; the farm is x86-64 only,
// and this keeps a stored tile readable by anything that knows "float32 little-endian".
static_assert(std::endian::native == std::endian::little);
static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559);

constexpr int schema_version = 3;

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
  rays INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX jobs_by_scene ON jobs(scene_digest);
CREATE TABLE tiles (
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  tile_index INTEGER NOT NULL,
  x INTEGER NOT NULL,
  y INTEGER NOT NULL,
  w INTEGER NOT NULL,
  h INTEGER NOT NULL,
  state TEXT NOT NULL,
  lease_id TEXT NOT NULL DEFAULT '',
  worker_id TEXT NOT NULL DEFAULT '',
  lease_expires_ms INTEGER NOT NULL DEFAULT 0,
  attempts INTEGER NOT NULL DEFAULT 0,
  rays INTEGER NOT NULL DEFAULT 0,
  result_lease_id TEXT NOT NULL DEFAULT '',
  last_error TEXT NOT NULL DEFAULT '',
  pixels_id INTEGER,  -- tile_pixels(id) of its accepted pixels; NULL before there are any
  PRIMARY KEY (job_id, tile_index)
);
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

// A done tile's pixels live apart from its row (schema version 3), in a table with no
// index but its integer key: storing a result appends there, and the tile row (small, and
// beside the rows of the same lease, since rows are stored in hand-out order) notes the
// key. Stored in the tile row itself, each result grew a small row to a whole page in
// place, which rewrote that page and its neighbours: about five pages per tile went through
// the WAL, and again into the database at the checkpoint. A key (job_id, tile_index) would
// scatter its index's updates over the whole job instead. The triggers drop pixels that
// their tile no longer points to.
constexpr const char* pixels_table_sql = R"sql(
CREATE TABLE tile_pixels (
  id INTEGER PRIMARY KEY,
  pixels BLOB NOT NULL
);
CREATE TRIGGER tile_pixels_replaced AFTER UPDATE OF pixels_id ON tiles
  WHEN old.pixels_id IS NOT NULL AND old.pixels_id IS NOT new.pixels_id
  BEGIN DELETE FROM tile_pixels WHERE id = old.pixels_id; END;
CREATE TRIGGER tile_pixels_deleted AFTER DELETE ON tiles
  WHEN old.pixels_id IS NOT NULL
  BEGIN DELETE FROM tile_pixels WHERE id = old.pixels_id; END;
)sql";

// The SQLite page cache, at most (a negative cache_size is KiB). The tiles being handed
// out and delivered stay in it; the default 2 MiB read them back from the file again and
// again on a big job.
constexpr int cache_kib = 32 * 1024;

// Creates the directories before the database file is opened in them.
std::filesystem::path prepare_data_dir(const std::filesystem::path& data_dir) {
  std::filesystem::create_directories(data_dir / "images");
  return data_dir / "tessera.db";
}

// The columns a tile changes over its life, bound from parameter `first` on.
void bind_tile_state(Statement& s, const TileRow& tile, int first) {
  s.bind(first, tile.state)
      .bind(first + 1, tile.lease_id)
      .bind(first + 2, tile.worker_id)
      .bind(first + 3, tile.lease_expires_ms)
      .bind(first + 4, tile.attempts)
      .bind(first + 5, static_cast<std::int64_t>(tile.rays))
      .bind(first + 6, tile.result_lease_id)
      .bind(first + 7, tile.last_error);
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
    db_.exec(pixels_table_sql);
  }
  if (version == 1)  // before tiles remembered why they failed
    db_.exec("ALTER TABLE tiles ADD COLUMN last_error TEXT NOT NULL DEFAULT ''");
  if (version == 1 || version == 2) {  // before pixels had a table of their own
    db_.exec("ALTER TABLE tiles ADD COLUMN pixels_id INTEGER");
    db_.exec(pixels_table_sql);
    // The tile rows' own rowids are unique, so they serve as the new keys.
    db_.exec("INSERT INTO tile_pixels (id, pixels) SELECT rowid, pixels FROM tiles WHERE pixels IS NOT NULL");
    db_.exec("UPDATE tiles SET pixels_id = rowid WHERE pixels IS NOT NULL");
    db_.exec("ALTER TABLE tiles DROP COLUMN pixels");
  }
  db_.exec("PRAGMA user_version=" + std::to_string(schema_version));
  tx.commit();
}

std::filesystem::path Store::image_path(const std::string& job_id) const {
  return data_dir_ / "images" / (job_id + ".exr");
}

StoredState Store::load() {
  StoredState state;
  Transaction tx(db_);  // one snapshot for all three tables
  {
    auto s = db_.statement(
        "SELECT id, name, priority, state, width, height, tile_size, scene_digest, "
        "created_at_ms, started_at_ms, finished_at_ms, error, rays FROM jobs");
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
    }
  }
  {
    // length() of a blob is read from the record header; the pixels stay on disk.
    auto s = db_.statement(
        "SELECT job_id, tile_index, x, y, w, h, state, lease_id, worker_id, lease_expires_ms, "
        "attempts, rays, result_lease_id, "
        "ifnull((SELECT length(p.pixels) FROM tile_pixels p WHERE p.id = t.pixels_id), 0), "
        "last_error FROM tiles t ORDER BY job_id, tile_index");
    while (s->step()) {
      TileRow& tile = state.tiles.emplace_back();
      tile.job_id = s->column_text(0);
      tile.tile_index = s->column_int(1);
      tile.rect = {s->column_int(2), s->column_int(3), s->column_int(4), s->column_int(5)};
      tile.state = s->column_text(6);
      tile.lease_id = s->column_text(7);
      tile.worker_id = s->column_text(8);
      tile.lease_expires_ms = s->column_int64(9);
      tile.attempts = s->column_int(10);
      tile.rays = static_cast<std::uint64_t>(s->column_int64(11));
      tile.result_lease_id = s->column_text(12);
      tile.pixel_bytes = s->column_int64(13);
      tile.last_error = s->column_text(14);
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

void Store::insert_job(const JobRow& job, const std::string& scene_json,
                       std::span<const TileRow> tiles) {
  insert_job(job, scene_json, tiles.size(),
             [&](std::size_t i, TileRow& row) { row = tiles[i]; });
}

void Store::insert_job(const JobRow& job, const std::string& scene_json, std::size_t tile_count,
                       const std::function<void(std::size_t i, TileRow& row)>& tile_at) {
  Transaction tx(db_);
  db_.statement("INSERT OR IGNORE INTO scenes (digest, json) VALUES (?, ?)")
      ->bind(1, job.scene_digest)
      .bind(2, scene_json)
      .run();
  db_.statement(
         "INSERT INTO jobs (id, name, priority, state, width, height, tile_size, scene_digest, "
         "created_at_ms, started_at_ms, finished_at_ms, error, rays) "
         "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
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
      .run();
  TileRow tile;  // one at a time: a big job's rows are never all in memory at once
  for (std::size_t i = 0; i < tile_count; ++i) {
    tile_at(i, tile);
    auto s = db_.statement(
        "INSERT INTO tiles (job_id, tile_index, x, y, w, h, state, lease_id, worker_id, "
        "lease_expires_ms, attempts, rays, result_lease_id, last_error) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    s->bind(1, tile.job_id)
        .bind(2, tile.tile_index)
        .bind(3, tile.rect.x)
        .bind(4, tile.rect.y)
        .bind(5, tile.rect.width)
        .bind(6, tile.rect.height);
    bind_tile_state(*s, tile, 7);
    s->run();
  }
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
  db_.statement("DELETE FROM tiles WHERE job_id = ?")->bind(1, job_id).run();
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
}

std::optional<std::string> Store::scene_json(const std::string& digest) {
  auto s = db_.statement("SELECT json FROM scenes WHERE digest = ?");
  s->bind(1, digest);
  if (!s->step()) return std::nullopt;
  return s->column_text(0);
}

void Store::update_tile(const TileRow& tile) {
  auto s = db_.statement(
      "UPDATE tiles SET state = ?, lease_id = ?, worker_id = ?, lease_expires_ms = ?, "
      "attempts = ?, rays = ?, result_lease_id = ?, last_error = ? "
      "WHERE job_id = ? AND tile_index = ?");
  bind_tile_state(*s, tile, 1);
  s->bind(9, tile.job_id).bind(10, tile.tile_index).run();
}

void Store::store_tile_result(const TileRow& tile, std::span<const float> pixels) {
  // One transaction, so the pixels and the state that says they are there land together.
  Transaction tx(db_);
  store_tile_result(tx, tile, pixels);
  tx.commit();
}

void Store::store_tile_result(const Transaction&, const TileRow& tile, std::span<const float> pixels) {
  db_.statement("INSERT INTO tile_pixels (pixels) VALUES (?)")->bind_blob(1, std::as_bytes(pixels)).run();
  auto s = db_.statement(
      "UPDATE tiles SET state = ?, lease_id = ?, worker_id = ?, lease_expires_ms = ?, "
      "attempts = ?, rays = ?, result_lease_id = ?, last_error = ?, pixels_id = last_insert_rowid() "
      "WHERE job_id = ? AND tile_index = ?");
  bind_tile_state(*s, tile, 1);
  s->bind(9, tile.job_id).bind(10, tile.tile_index).run();
}

void Store::for_each_tile_pixels(
    const std::string& job_id,
    const std::function<void(int tile_index, std::span<const float>)>& visit) {
  auto s = db_.statement(
      "SELECT t.tile_index, p.pixels FROM tiles t JOIN tile_pixels p ON p.id = t.pixels_id "
      "WHERE t.job_id = ? ORDER BY t.tile_index");
  s->bind(1, job_id);
  std::vector<float> floats;  // a copy: SQLite's blob pointer need not be float-aligned
  while (s->step()) {
    const std::span<const std::byte> bytes = s->column_blob(1);
    floats.resize(bytes.size() / sizeof(float));
    if (!bytes.empty()) std::memcpy(floats.data(), bytes.data(), floats.size() * sizeof(float));
    visit(s->column_int(0), floats);
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
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(data_dir_ / "images", error)) {
    const std::filesystem::path& path = entry.path();
    if (path.extension() != ".exr") continue;
    const std::string stem = path.stem().string();
    // write_image's temporary files start with a dot; one left over is a crashed write.
    if (stem.starts_with(".") || !keep(stem)) {
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
    }
  }
}

}  // namespace tessera
