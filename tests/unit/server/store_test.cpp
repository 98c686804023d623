#include "server/farm/sqlite_store.hpp"

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <span>
#include <thread>

#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "server/farm/image_files.hpp"
#include "server/farm/sqlite_db.hpp"

namespace tessera {
namespace {

JobRow job_row(const std::string& id, const std::string& digest) {
  JobRow job;
  job.id = id;
  job.name = "name of " + id;
  job.priority = 70;
  job.state = "queued";
  job.width = 40;
  job.height = 20;
  job.tile_size = 20;
  job.scene_digest = digest;
  job.created_at_ms = 1234;
  return job;
}

// Version 7 had no animations: every job was a still.
void make_version_7(SqliteDb& db) {
  db.exec("ALTER TABLE jobs DROP COLUMN frames");
  db.exec("PRAGMA user_version=7");
}

// Version 6 could not drain workers.
void make_version_6(SqliteDb& db) {
  make_version_7(db);
  db.exec("ALTER TABLE workers DROP COLUMN draining");
  db.exec("PRAGMA user_version=6");
}

// Version 5 kept no digest of a worker's secret either.
void make_version_5(SqliteDb& db) {
  make_version_6(db);
  db.exec("ALTER TABLE workers DROP COLUMN secret_sha256");
  db.exec("PRAGMA user_version=5");
}

// Version 4 kept no facts of the scene on the job row either.
void make_version_4(SqliteDb& db) {
  make_version_5(db);
  db.exec("ALTER TABLE jobs DROP COLUMN output_transfer");
  db.exec("PRAGMA user_version=4");
}

// Turns a new database into what version 3 wrote: jobs with a row per tile, done tiles'
// pixels in a table of their own. Tile 0 failed once, tile 1 is done (its pixels given),
// tiles 2 and 3 are leased to worker w-1 under lease l-1.
void make_version_3(SqliteDb& db, const std::string& job_id, std::span<const float> pixels) {
  make_version_4(db);
  db.exec("DROP TABLE leases; DROP TABLE results; DROP TABLE tile_failures");
  db.exec(R"sql(
CREATE TABLE tiles (
  job_id TEXT NOT NULL REFERENCES jobs(id) ON DELETE CASCADE,
  tile_index INTEGER NOT NULL,
  x INTEGER NOT NULL, y INTEGER NOT NULL, w INTEGER NOT NULL, h INTEGER NOT NULL,
  state TEXT NOT NULL,
  lease_id TEXT NOT NULL DEFAULT '',
  worker_id TEXT NOT NULL DEFAULT '',
  lease_expires_ms INTEGER NOT NULL DEFAULT 0,
  attempts INTEGER NOT NULL DEFAULT 0,
  rays INTEGER NOT NULL DEFAULT 0,
  result_lease_id TEXT NOT NULL DEFAULT '',
  last_error TEXT NOT NULL DEFAULT '',
  pixels_id INTEGER,
  PRIMARY KEY (job_id, tile_index)
);
CREATE TABLE tile_pixels (id INTEGER PRIMARY KEY, pixels BLOB NOT NULL);
CREATE TRIGGER tile_pixels_replaced AFTER UPDATE OF pixels_id ON tiles
  WHEN old.pixels_id IS NOT NULL AND old.pixels_id IS NOT new.pixels_id
  BEGIN DELETE FROM tile_pixels WHERE id = old.pixels_id; END;
CREATE TRIGGER tile_pixels_deleted AFTER DELETE ON tiles
  WHEN old.pixels_id IS NOT NULL
  BEGIN DELETE FROM tile_pixels WHERE id = old.pixels_id; END;
)sql");
  for (int i = 0; i < 4; ++i)
    db.statement(
          "INSERT INTO tiles (job_id, tile_index, x, y, w, h, state) VALUES (?, ?, ?, ?, 20, 20, "
          "'pending')")
        ->bind(1, job_id)
        .bind(2, i)
        .bind(3, (i % 2) * 20)
        .bind(4, (i / 2) * 20)
        .run();
  db.exec("UPDATE tiles SET attempts = 1, last_error = 'it broke' WHERE tile_index = 0");
  db.statement("INSERT INTO tile_pixels (id, pixels) VALUES (7, ?)")
      ->bind_blob(1, std::as_bytes(pixels))
      .run();
  db.exec(
      "UPDATE tiles SET state = 'done', worker_id = 'w-2', rays = 77, result_lease_id = 'l-0', "
      "pixels_id = 7 WHERE tile_index = 1");
  db.exec(
      "UPDATE tiles SET state = 'leased', lease_id = 'l-1', worker_id = 'w-1', lease_expires_ms = "
      "5 "
      "WHERE tile_index >= 2");
  db.exec("PRAGMA user_version=3");
}

// Version 2 kept a done tile's pixels in its row.
void make_version_2(SqliteDb& db) {
  db.exec("ALTER TABLE tiles ADD COLUMN pixels BLOB");
  db.exec(
      "UPDATE tiles SET pixels = (SELECT p.pixels FROM tile_pixels p WHERE p.id = "
      "tiles.pixels_id)");
  db.exec("DROP TRIGGER tile_pixels_replaced");
  db.exec("DROP TRIGGER tile_pixels_deleted");
  db.exec("DROP TABLE tile_pixels");
  db.exec("ALTER TABLE tiles DROP COLUMN pixels_id");
  db.exec("PRAGMA user_version=2");
}

JobRow square_job(const std::string& id, const std::string& digest) {  // 2 x 2 tiles
  JobRow job = job_row(id, digest);
  job.width = 40;
  job.height = 40;
  return job;
}

std::vector<float> numbered_pixels(std::size_t count, float start) {
  std::vector<float> pixels(count);
  for (std::size_t i = 0; i < count; ++i)
    pixels[i] = start + static_cast<float>(i) * -0.1f + 1e-40f;  // includes denormals
  return pixels;
}

ResultRow result_row(const std::string& job_id, std::vector<int> tiles) {
  ResultRow result;
  result.job_id = job_id;
  result.lease_id = "l-9";
  result.worker_id = "w-9";
  for (std::size_t i = 0; i < tiles.size(); ++i) result.rays.push_back(100 + i);
  result.tiles = std::move(tiles);
  return result;
}

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("tessera-store-test-" + std::to_string(::getpid()) + "-" + info->name()) / "data";
    std::filesystem::remove_all(dir_.parent_path());
    store_ = std::make_unique<SqliteStore>(dir_);
  }
  void TearDown() override {
    store_.reset();
    std::filesystem::remove_all(dir_.parent_path());
  }
  void reopen() {
    store_.reset();
    store_ = std::make_unique<SqliteStore>(dir_);
  }

  std::filesystem::path dir_;
  std::unique_ptr<SqliteStore> store_;
};

// The pixels the store has for each tile of job "j-1", 20 x 20 tiles, in stored order.
std::vector<std::pair<int, std::vector<float>>> stored_pixels(Store& store) {
  std::vector<std::pair<int, std::vector<float>>> tiles;
  store.for_each_tile_pixels(
      "j-1", [](int) -> std::size_t { return 20 * 20 * 3; },
      [&](int index, std::span<const float> pixels) {
        tiles.emplace_back(index, std::vector<float>(pixels.begin(), pixels.end()));
      });
  return tiles;
}

bool same_bits(const std::vector<float>& a, std::span<const float> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), b.size_bytes()) == 0;
}

TEST_F(StoreTest, CreatesTheDirectoryAndAWalDatabaseWithASchemaVersion) {
  EXPECT_EQ(store_->data_dir(), dir_);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "tessera.db"));
  EXPECT_TRUE(std::filesystem::is_directory(dir_ / "pixels"));
  SqliteDb db(dir_ / "tessera.db");
  EXPECT_EQ(db.query_text("PRAGMA journal_mode"), "wal");
  EXPECT_EQ(db.query_text("PRAGMA user_version"), "8");
}

TEST_F(StoreTest, RefusesADatabaseFromANewerVersion) {
  store_.reset();
  SqliteDb(dir_ / "tessera.db").exec("PRAGMA user_version=99");
  try {
    SqliteStore store(dir_);
    FAIL() << "opened a database of schema version 99";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("schema version 99"), std::string::npos) << e.what();
  }
}

// What version 3's tile rows become: the failure, the done tile as a result of its own, the
// leased tiles as their lease; no row per tile is left.
void expect_upgraded(Store& store, const std::filesystem::path& db_file,
                     const std::vector<float>& pixels, bool with_failure) {
  SqliteDb db(db_file);
  EXPECT_EQ(db.query_text("PRAGMA user_version"), "8");
  EXPECT_EQ(
      db.query_text("SELECT count(*) FROM sqlite_schema WHERE name IN ('tiles', 'tile_pixels')"),
      "0");
  const StoredState state = store.load();
  ASSERT_EQ(state.jobs.size(), 1u);
  if (with_failure) {
    ASSERT_EQ(state.failures.size(), 1u);
    EXPECT_EQ(state.failures[0].tile_index, 0);
    EXPECT_EQ(state.failures[0].attempts, 1);
    EXPECT_EQ(state.failures[0].last_error, "it broke");
  }
  ASSERT_EQ(state.results.size(), 1u);
  EXPECT_EQ(state.results[0].tiles, std::vector<int>{1});
  EXPECT_EQ(state.results[0].rays, std::vector<std::uint64_t>{77});
  EXPECT_EQ(state.results[0].lease_id, "l-0");
  EXPECT_EQ(state.results[0].worker_id, "w-2");
  EXPECT_EQ(state.results[0].pixel_bytes, static_cast<std::int64_t>(pixels.size() * 4));
  ASSERT_EQ(state.leases.size(), 1u);
  EXPECT_EQ(state.leases[0].id, "l-1");
  EXPECT_EQ(state.leases[0].worker_id, "w-1");
  EXPECT_EQ(state.leases[0].tiles, (std::vector<int>{2, 3}));
  const auto tiles = stored_pixels(store);
  ASSERT_EQ(tiles.size(), 1u);
  EXPECT_EQ(tiles[0].first, 1);
  EXPECT_TRUE(same_bits(tiles[0].second, pixels));
}

TEST_F(StoreTest, UpgradesAVersion3DatabaseIntoLeasesResultsAndFailures) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  store_.reset();
  const std::vector<float> pixels = numbered_pixels(20 * 20 * 3, 1.0f);
  {
    SqliteDb db(dir_ / "tessera.db");
    make_version_3(db, "j-1", pixels);
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  expect_upgraded(*store_, dir_ / "tessera.db", pixels, true);
}

TEST_F(StoreTest, UpgradesAVersion2DatabaseWithThePixelsInTheTileRows) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  store_.reset();
  const std::vector<float> pixels = numbered_pixels(20 * 20 * 3, 2.0f);
  {
    SqliteDb db(dir_ / "tessera.db");
    make_version_3(db, "j-1", pixels);
    make_version_2(db);
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  expect_upgraded(*store_, dir_ / "tessera.db", pixels, true);
}

TEST_F(StoreTest, UpgradesAVersion1DatabaseWhoseTilesHadNoErrors) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  store_.reset();
  const std::vector<float> pixels = numbered_pixels(20 * 20 * 3, 3.0f);
  {
    SqliteDb db(dir_ / "tessera.db");
    make_version_3(db, "j-1", pixels);
    make_version_2(db);
    db.exec("ALTER TABLE tiles DROP COLUMN last_error");
    db.exec("PRAGMA user_version=1");
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  expect_upgraded(*store_, dir_ / "tessera.db", pixels, false);
  const StoredState state = store_->load();
  ASSERT_EQ(state.failures.size(), 1u);  // attempts were kept, with no error to say
  EXPECT_EQ(state.failures[0].last_error, "");
}

TEST_F(StoreTest, UpgradesAVersion4DatabaseReadingEachJobsOutputTransferFromItsScene) {
  store_->insert_job(square_job("j-1", "d1"), R"({"render": {"output_transfer": "linear"}})");
  store_->insert_job(square_job("j-2", "d2"), R"({"render": {"output_transfer": "srgb"}})");
  store_->insert_job(square_job("j-3", "d3"), "{}");
  store_.reset();
  {
    SqliteDb db(dir_ / "tessera.db");
    make_version_4(db);
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  EXPECT_EQ(SqliteDb(dir_ / "tessera.db").query_text("PRAGMA user_version"), "8");
  std::map<std::string, std::string> transfers;
  for (const JobRow& job : store_->load().jobs) transfers[job.id] = job.output_transfer;
  EXPECT_EQ(transfers, (std::map<std::string, std::string>{
                           {"j-1", "linear"}, {"j-2", "srgb"}, {"j-3", "srgb"}}));
}

// A worker of a version 5 store had no secret: it loads with none, so that it cannot prove
// itself and registers again.
TEST_F(StoreTest, UpgradesAVersion5DatabaseWhoseWorkersHadNoSecrets) {
  store_->upsert_worker({"w-1", "box", "10.0.0.2", 4, "idle", 3, 1000, "will be dropped"});
  store_.reset();
  {
    SqliteDb db(dir_ / "tessera.db");
    make_version_5(db);
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  EXPECT_EQ(SqliteDb(dir_ / "tessera.db").query_text("PRAGMA user_version"), "8");
  const StoredState state = store_->load();
  ASSERT_EQ(state.workers.size(), 1u);
  EXPECT_EQ(state.workers[0].name, "box");
  EXPECT_EQ(state.workers[0].tiles_rendered, 3u);
  EXPECT_EQ(state.workers[0].secret_sha256, "");
}

// A worker of a version 6 store was never drained: it loads taking tiles.
TEST_F(StoreTest, UpgradesAVersion6DatabaseWhoseWorkersWereNeverDrained) {
  store_->upsert_worker({"w-1", "box", "10.0.0.2", 4, "idle", 3, 1000, "digest", true});
  store_.reset();
  {
    SqliteDb db(dir_ / "tessera.db");
    make_version_6(db);
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  EXPECT_EQ(SqliteDb(dir_ / "tessera.db").query_text("PRAGMA user_version"), "8");
  const StoredState state = store_->load();
  ASSERT_EQ(state.workers.size(), 1u);
  EXPECT_EQ(state.workers[0].secret_sha256, "digest");
  EXPECT_FALSE(state.workers[0].draining);
  store_->upsert_worker({"w-1", "box", "10.0.0.2", 4, "idle", 3, 1000, "digest", true});
  EXPECT_TRUE(store_->load().workers[0].draining);
}

// A job of a version 7 store is a still: its frames are "".
TEST_F(StoreTest, UpgradesAVersion7DatabaseWhoseJobsWereStills) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  store_.reset();
  {
    SqliteDb db(dir_ / "tessera.db");
    make_version_7(db);
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  EXPECT_EQ(SqliteDb(dir_ / "tessera.db").query_text("PRAGMA user_version"), "8");
  ASSERT_EQ(store_->load().jobs.size(), 1u);
  EXPECT_EQ(store_->load().jobs[0].frames, "");
}

TEST_F(StoreTest, AJobKeepsItsFrames) {
  JobRow job = square_job("j-1", "d1");
  job.frames = "1-48x2,99";
  store_->insert_job(job, "{}");
  reopen();
  ASSERT_EQ(store_->load().jobs.size(), 1u);
  EXPECT_EQ(store_->load().jobs[0].frames, "1-48x2,99");
}

// One frame of an animation is read without the others' pixels: a result none of whose
// tiles is wanted is skipped whole.
TEST_F(StoreTest, ResultsOfUnwantedTilesAreNotRead) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  const std::vector<float> first = numbered_pixels(20 * 20 * 3, 1.0f);
  const std::vector<float> second = numbered_pixels(20 * 20 * 3, 2.0f);
  const std::span<const float> a(first), b(second);
  store_->insert_result({0, "j-1", "l-1", "w-1", {0}, {1}}, {&a, 1});
  store_->insert_result({0, "j-1", "l-2", "w-1", {3}, {1}}, {&b, 1});
  std::map<int, float> seen;
  store_->for_each_tile_pixels(
      "j-1", [](int) { return std::size_t{20 * 20 * 3}; },
      [&](int index, std::span<const float> pixels) { seen[index] = pixels[0]; },
      [](int index) { return index == 3; });
  EXPECT_EQ(seen, (std::map<int, float>{{3, second[0]}}));
}

TEST_F(StoreTest, AJobKeepsItsOutputTransfer) {
  JobRow job = square_job("j-1", "d1");
  job.output_transfer = "linear";
  store_->insert_job(job, "{}");
  reopen();
  ASSERT_EQ(store_->load().jobs.size(), 1u);
  EXPECT_EQ(store_->load().jobs[0].output_transfer, "linear");
}

TEST_F(StoreTest, AnUploadIsOneRowHoweverManyTilesItHolds) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  // Tile 3's pixels in a buffer of their own, tiles 0 and 2 one after the other: both kinds
  // of upload are stored alike.
  const std::vector<float> adjacent = numbered_pixels(2 * 20 * 20 * 3, 5.0f);
  const std::vector<float> apart = numbered_pixels(20 * 20 * 3, 9.0f);
  const std::span<const float> all(adjacent);
  const std::vector<std::span<const float>> first{all.first(1200), all.subspan(1200)};
  const std::vector<std::span<const float>> second{apart};
  const std::vector<std::span<const float>> mixed{all.subspan(1200), apart};
  const std::int64_t a = store_->insert_result(result_row("j-1", {0, 2}), first);
  const std::int64_t b = store_->insert_result(result_row("j-1", {3}), second);
  SqliteDb db(dir_ / "tessera.db");
  EXPECT_EQ(db.query_text("SELECT count(*) FROM results"), "2");
  EXPECT_LT(a, b);

  reopen();
  const StoredState state = store_->load();
  ASSERT_EQ(state.results.size(), 2u);
  EXPECT_EQ(state.results[0].tiles, (std::vector<int>{0, 2}));
  EXPECT_EQ(state.results[0].rays, (std::vector<std::uint64_t>{100, 101}));
  EXPECT_EQ(state.results[0].lease_id, "l-9");
  EXPECT_EQ(state.results[0].worker_id, "w-9");
  EXPECT_EQ(state.results[0].pixel_bytes, 2 * 20 * 20 * 3 * 4);
  const auto tiles = stored_pixels(*store_);
  ASSERT_EQ(tiles.size(), 3u);
  EXPECT_EQ(tiles[0].first, 0);
  EXPECT_TRUE(same_bits(tiles[0].second, all.first(1200)));
  EXPECT_EQ(tiles[1].first, 2);
  EXPECT_TRUE(same_bits(tiles[1].second, all.subspan(1200)));
  EXPECT_EQ(tiles[2].first, 3);
  EXPECT_TRUE(same_bits(tiles[2].second, apart));

  // Tiles gathered from separate buffers read back the same.
  store_->delete_result(a);
  store_->delete_result(b);
  store_->insert_result(result_row("j-1", {2, 3}), mixed);
  const auto again = stored_pixels(*store_);
  ASSERT_EQ(again.size(), 2u);
  EXPECT_TRUE(same_bits(again[0].second, all.subspan(1200)));
  EXPECT_TRUE(same_bits(again[1].second, apart));
}

TEST_F(StoreTest, PixelsThatEndEarlyAreAnErrorNamingTheJobAndTile) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  const std::vector<float> short_pixels(20 * 20 * 3 + 5, 1.0f);
  const std::vector<std::span<const float>> tiles{short_pixels};
  store_->insert_result(result_row("j-1", {0, 1}), tiles);
  EXPECT_EQ(store_->load().results[0].pixel_bytes,
            static_cast<std::int64_t>(short_pixels.size() * 4));
  try {
    stored_pixels(*store_);
    FAIL() << "read past the stored pixels";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("job j-1 end before tile 1"), std::string::npos)
        << e.what();
  }
}

TEST_F(StoreTest, ALeaseIsReplacedWholeAndDeleted) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  store_->put_lease({"l-1", "j-1", "w-1", {3, 1}});
  store_->put_lease({"l-2", "j-1", "w-2", {0}});
  store_->put_lease({"l-1", "j-1", "w-1", {3, 1, 2}});  // extended
  store_->delete_lease("l-2");                          // delivered or given back
  reopen();
  const StoredState state = store_->load();
  ASSERT_EQ(state.leases.size(), 1u);
  EXPECT_EQ(state.leases[0].id, "l-1");
  EXPECT_EQ(state.leases[0].job_id, "j-1");
  EXPECT_EQ(state.leases[0].worker_id, "w-1");
  EXPECT_EQ(state.leases[0].tiles, (std::vector<int>{3, 1, 2}));
}

TEST_F(StoreTest, TheWalIsCheckpointedWhileTheStoreWrites) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  // More than a thousand pages of results (each lists 1,000 tiles: 12 KB of indexes and
  // rays): the store's own commits do not checkpoint (its automatic checkpoint is off), its
  // checkpointer thread does, so the database file grows before the store is closed.
  std::vector<int> tiles(1000);
  for (int i = 0; i < 1000; ++i) tiles[i] = i;
  for (int round = 0; round < 400; ++round) store_->insert_result(result_row("j-1", tiles), {});
  const auto db_size = [&] { return std::filesystem::file_size(dir_ / "tessera.db"); };
  const auto start = std::chrono::steady_clock::now();
  while (db_size() < 4096 * 4 &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_GE(db_size(), 4096u * 4) << "nothing was checkpointed into the database file";
  reopen();
  EXPECT_EQ(store_->load().results.size(), 400u);
}

TEST_F(StoreTest, PixelsGoToTheJobsOwnFileAndLoadSaysHowMuchOfThemItHolds) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  const std::vector<float> a = numbered_pixels(20 * 20 * 3, 1.0f);
  const std::vector<float> b = numbered_pixels(20 * 20 * 3, 2.0f);
  store_->insert_result(result_row("j-1", {0}), std::vector<std::span<const float>>{a});
  store_->insert_result(result_row("j-1", {1}), std::vector<std::span<const float>>{b});
  const std::filesystem::path file = store_->pixel_path("j-1");
  EXPECT_EQ(file, dir_ / "pixels" / "j-1.f32");
  ASSERT_EQ(std::filesystem::file_size(file), 2u * 1200 * 4);
  // Power lost before the second upload's pixels were all on disk.
  store_.reset();
  std::filesystem::resize_file(file, 1200 * 4 + 10);
  store_ = std::make_unique<SqliteStore>(dir_);
  const StoredState state = store_->load();
  ASSERT_EQ(state.results.size(), 2u);
  EXPECT_EQ(state.results[0].pixel_bytes, 1200 * 4);
  EXPECT_EQ(state.results[1].pixel_bytes, 10);
  // The next upload goes after what is there, wherever the last one ended.
  store_->delete_result(state.results[1].id);
  store_->insert_result(result_row("j-1", {1}), std::vector<std::span<const float>>{b});
  const auto tiles = stored_pixels(*store_);
  ASSERT_EQ(tiles.size(), 2u);
  EXPECT_TRUE(same_bits(tiles[0].second, a));
  EXPECT_TRUE(same_bits(tiles[1].second, b));
  EXPECT_EQ(store_->load().results[1].pixel_bytes, 1200 * 4);

  store_->delete_job("j-1");
  EXPECT_FALSE(std::filesystem::exists(file));
}

TEST_F(StoreTest, ARowThatPointsOutsideItsFileIsReportedAsHoldingNothing) {
  store_->insert_job(square_job("j-1", "d1"), "{}");
  const std::vector<float> a = numbered_pixels(20 * 20 * 3, 1.0f);
  store_->insert_result(result_row("j-1", {0}), std::vector<std::span<const float>>{a});
  store_->insert_result(result_row("j-1", {1}), std::vector<std::span<const float>>{a});
  store_.reset();
  {  // a damaged database: one row starts before the file, another has a negative size
    SqliteDb db(dir_ / "tessera.db");
    db.exec("UPDATE results SET pixels_at = -4 WHERE id = (SELECT min(id) FROM results)");
    db.exec("UPDATE results SET pixel_bytes = -1 WHERE id = (SELECT max(id) FROM results)");
  }
  store_ = std::make_unique<SqliteStore>(dir_);
  const StoredState state = store_->load();
  ASSERT_EQ(state.results.size(), 2u);
  EXPECT_EQ(state.results[0].pixel_bytes, 0);
  EXPECT_EQ(state.results[1].pixel_bytes, 0);
}

TEST_F(StoreTest, AFullDiskIsNamedAsSuch) {
  // /dev/full answers every write with ENOSPC.
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  store_->insert_job(square_job("j-1", "d1"), "{}");
  std::filesystem::create_symlink("/dev/full", store_->pixel_path("j-1"));
  const std::vector<float> pixels(1200, 1.0f);
  try {
    store_->insert_result(result_row("j-1", {0}), std::vector<std::span<const float>>{pixels});
    FAIL() << "stored pixels on a full disk";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("the disk is full"), std::string::npos) << message;
    EXPECT_NE(message.find("j-1.f32"), std::string::npos) << message;
  }
  EXPECT_TRUE(store_->load().results.empty());
}

TEST_F(StoreTest, JobsFailuresScenesAndWorkersSurviveAReopen) {
  store_->insert_job(job_row("j-1", "d1"), R"({"scene":1})");
  store_->put_tile_failure({"j-1", 1, 1, "first"});
  store_->put_tile_failure({"j-1", 1, 2, "second"});
  JobRow running = job_row("j-1", "d1");
  running.state = "running";
  running.started_at_ms = 1300;
  running.rays = (std::uint64_t{1} << 40) + 3;  // beyond 32 bits
  store_->update_job(running);
  WorkerRow worker{"w-1", "box", "10.0.0.2", 16, "rendering", 5, 2000, "digest"};
  store_->upsert_worker(worker);
  worker.state = "idle";
  worker.tiles_rendered = 6;
  store_->upsert_worker(worker);
  store_->update_worker_seen("w-1", 2500);

  reopen();
  const StoredState state = store_->load();
  ASSERT_EQ(state.jobs.size(), 1u);
  EXPECT_EQ(state.jobs[0].name, "name of j-1");
  EXPECT_EQ(state.jobs[0].state, "running");
  EXPECT_EQ(state.jobs[0].priority, 70);
  EXPECT_EQ(state.jobs[0].width, 40);
  EXPECT_EQ(state.jobs[0].tile_size, 20);
  EXPECT_EQ(state.jobs[0].started_at_ms, 1300);
  EXPECT_EQ(state.jobs[0].rays, (std::uint64_t{1} << 40) + 3);
  ASSERT_EQ(state.failures.size(), 1u);
  EXPECT_EQ(state.failures[0].job_id, "j-1");
  EXPECT_EQ(state.failures[0].tile_index, 1);
  EXPECT_EQ(state.failures[0].attempts, 2);
  EXPECT_EQ(state.failures[0].last_error, "second");
  EXPECT_TRUE(state.leases.empty());
  EXPECT_TRUE(state.results.empty());
  ASSERT_EQ(state.workers.size(), 1u);
  EXPECT_EQ(state.workers[0].host, "10.0.0.2");
  EXPECT_EQ(state.workers[0].threads, 16);
  EXPECT_EQ(state.workers[0].state, "idle");
  EXPECT_EQ(state.workers[0].tiles_rendered, 6u);
  EXPECT_EQ(state.workers[0].last_seen_ms, 2500);
  EXPECT_EQ(state.workers[0].secret_sha256, "digest");
  EXPECT_EQ(store_->scene_json("d1"), R"({"scene":1})");
  EXPECT_FALSE(store_->scene_json("d2"));
}

TEST_F(StoreTest, DeleteJobTakesItsRowsPixelsAndOrphanedSceneOnly) {
  const std::vector<float> pixels(20 * 20 * 3, 1.0f);
  const std::vector<std::span<const float>> tiles{pixels};
  for (const char* id : {"j-1", "j-2"}) {
    store_->insert_job(square_job(id, "shared"), "{}");
    store_->put_lease({std::string("l-") + id, id, "w-1", {0}});
    store_->insert_result(result_row(id, {1}), tiles);
    store_->put_tile_failure({id, 2, 1, "broke"});
  }
  store_->insert_job(square_job("j-3", "own"), "{}");
  ASSERT_TRUE(std::filesystem::exists(store_->pixel_path("j-1")));

  store_->delete_job("j-1");
  EXPECT_FALSE(std::filesystem::exists(store_->pixel_path("j-1")));
  EXPECT_TRUE(std::filesystem::exists(store_->pixel_path("j-2")));
  EXPECT_TRUE(store_->scene_json("shared"));
  store_->delete_job("j-3");
  EXPECT_FALSE(store_->scene_json("own"));
  const StoredState state = store_->load();
  ASSERT_EQ(state.jobs.size(), 1u);
  EXPECT_EQ(state.jobs[0].id, "j-2");
  ASSERT_EQ(state.leases.size(), 1u);
  EXPECT_EQ(state.leases[0].job_id, "j-2");
  ASSERT_EQ(state.results.size(), 1u);
  EXPECT_EQ(state.results[0].job_id, "j-2");
  ASSERT_EQ(state.failures.size(), 1u);
  EXPECT_EQ(state.failures[0].job_id, "j-2");
}

TEST_F(StoreTest, AChangeThatThrowsRollsBackWhole) {
  EXPECT_THROW(store_->atomically([&] {
    store_->insert_job(job_row("j-1", "d1"), "{}");  // a savepoint within
    throw std::runtime_error("refused");
  }),
               std::runtime_error);
  EXPECT_TRUE(store_->load().jobs.empty());
  EXPECT_FALSE(store_->scene_json("d1"));
  store_->atomically([&] { store_->insert_job(job_row("j-1", "d1"), "{}"); });
  EXPECT_EQ(store_->load().jobs.size(), 1u);
}

TEST_F(StoreTest, FailuresNameTheOperationAndSqlitesMessage) {
  store_->insert_job(job_row("j-1", "d1"), "{}");
  try {
    store_->insert_job(job_row("j-1", "d1"), "{}");
    FAIL() << "inserted a job twice";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("UNIQUE constraint failed: jobs.id"), std::string::npos) << message;
    EXPECT_NE(message.find("INSERT INTO jobs"), std::string::npos) << message;
  }
  // The failed insert left nothing behind, and the store still works.
  EXPECT_EQ(store_->load().jobs.size(), 1u);
  store_->update_job(job_row("j-1", "d1"));
}

TEST_F(StoreTest, ImageFilesBesideTheStorePruneUnkeptImagesAndLeftovers) {
  const ImageFiles images(dir_);
  images.write("j-keep", Image(2, 2));
  images.write("j-drop", Image(2, 2));
  EXPECT_EQ(images.path("j-keep"), dir_ / "images" / "j-keep.exr");
  std::ofstream(dir_ / "images" / ".j-keep.tmp123.exr") << "partial";
  std::ofstream(dir_ / "images" / "notes.txt") << "not ours";
  images.prune([](const std::string& id) { return id == "j-keep"; });
  EXPECT_TRUE(images.has("j-keep"));
  EXPECT_FALSE(images.has("j-drop"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "images" / ".j-keep.tmp123.exr"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "images" / "notes.txt"));
}

// The coordinator's images are RLE EXRs (ZIP took six times as long on the cores that
// render), holding the floats exactly.
TEST_F(StoreTest, ImageFilesAreLosslessRleExrs) {
  const ImageFiles images(dir_);
  Image image(5, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) {
      const float rgb[3] = {x * 0.37f + 1e-7f, y * 11.3f, -0.0f + x * y * 1e5f};
      image.paste({x, y, 1, 1}, rgb);
    }
  images.write("j-1.f3", image);
  const Image back = read_image(images.path("j-1.f3"));
  ASSERT_EQ(back.pixels().size(), image.pixels().size());
  EXPECT_EQ(std::memcmp(back.pixels().data(), image.pixels().data(), image.pixels().size_bytes()),
            0);
  // The header's "compression" attribute: its name, its type's name, 1 byte, 1 for RLE.
  std::ifstream file(images.path("j-1.f3"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::string attribute("compression\0compression\0\x01\0\0\0", 28);
  const std::size_t at = bytes.find(attribute);
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(static_cast<int>(bytes.at(at + attribute.size())), 1) << "not RLE";
}

}  // namespace
}  // namespace tessera
