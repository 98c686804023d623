// The SQLite store's schema, and the upgrades from each older version of it.
#include <map>
#include <stdexcept>
#include <string>

#include "server/farm/sqlite_store.hpp"

namespace tessera {
namespace {

constexpr int schema_version = 8;

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
  output_transfer TEXT NOT NULL DEFAULT 'srgb',  -- the scene's render.output_transfer
  frames TEXT NOT NULL DEFAULT ''  -- an animation's frame list; '' for a still (frame 0)
);
CREATE INDEX jobs_by_scene ON jobs(scene_digest);
CREATE TABLE workers (
  id TEXT PRIMARY KEY,
  name TEXT NOT NULL,
  host TEXT NOT NULL,
  threads INTEGER NOT NULL,
  state TEXT NOT NULL,
  tiles_rendered INTEGER NOT NULL DEFAULT 0,
  last_seen_ms INTEGER NOT NULL,
  secret_sha256 TEXT NOT NULL DEFAULT '',  -- of the secret its registration was given
  draining INTEGER NOT NULL DEFAULT 0  -- 1: it takes no more tiles
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

}  // namespace

void SqliteStore::create_schema() {
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
  // Before workers had secrets: a worker of an older store is no longer known, and
  // registers again (the workers table is created with the column from version 6 on).
  if (version >= 1 && version <= 5)
    db_.exec("ALTER TABLE workers ADD COLUMN secret_sha256 TEXT NOT NULL DEFAULT ''");
  if (version >= 1 && version <= 6)  // before workers could be drained
    db_.exec("ALTER TABLE workers ADD COLUMN draining INTEGER NOT NULL DEFAULT 0");
  if (version >= 1 && version <= 7)  // before jobs rendered frames of animations
    db_.exec("ALTER TABLE jobs ADD COLUMN frames TEXT NOT NULL DEFAULT ''");
  db_.exec("PRAGMA user_version=" + std::to_string(schema_version));
  tx.commit();
}

void SqliteStore::migrate_tile_rows() {
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

}  // namespace tessera
