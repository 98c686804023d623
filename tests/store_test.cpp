#include "server/store.hpp"

#include <chrono>
#include <cstring>
#include <filesystem>
#include <span>
#include <thread>
#include <fstream>
#include <memory>

#include <gtest/gtest.h>

#include "server/sqlite_db.hpp"

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

std::vector<TileRow> tile_rows(const std::string& job_id) {
  std::vector<TileRow> tiles(2);
  for (int i = 0; i < 2; ++i) {
    tiles[i].job_id = job_id;
    tiles[i].tile_index = i;
    tiles[i].rect = {i * 20, 0, 20, 20};
    tiles[i].state = "pending";
  }
  return tiles;
}

// Turns a database of this version back into the schema of version 2, which kept a done
// tile's pixels in its row.
void make_version_2(SqliteDb& db) {
  db.exec("DROP TRIGGER tile_pixels_replaced");
  db.exec("DROP TRIGGER tile_pixels_deleted");
  db.exec("DROP TABLE tile_pixels");
  db.exec("ALTER TABLE tiles DROP COLUMN pixels_id");
  db.exec("ALTER TABLE tiles ADD COLUMN pixels BLOB");
  db.exec("PRAGMA user_version=2");
}

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("tessera-store-test-" + std::to_string(::getpid()) + "-" + info->name()) / "data";
    std::filesystem::remove_all(dir_.parent_path());
    store_ = std::make_unique<Store>(dir_);
  }
  void TearDown() override {
    store_.reset();
    std::filesystem::remove_all(dir_.parent_path());
  }
  void reopen() {
    store_.reset();
    store_ = std::make_unique<Store>(dir_);
  }

  std::filesystem::path dir_;
  std::unique_ptr<Store> store_;
};

// The store holds pixels for tile 1 of job "j-1" and for no other tile of it.
void expect_only_pixels_of_tile_1(Store& store, const std::vector<float>& pixels) {
  int visits = 0;
  store.for_each_tile_pixels("j-1", [&](int index, std::span<const float> stored) {
    ++visits;
    EXPECT_EQ(index, 1);
    ASSERT_EQ(stored.size(), pixels.size());
    EXPECT_EQ(std::memcmp(stored.data(), pixels.data(), stored.size_bytes()), 0);
  });
  EXPECT_EQ(visits, 1);
}

TEST_F(StoreTest, CreatesTheDirectoryAndAWalDatabaseWithASchemaVersion) {
  EXPECT_EQ(store_->data_dir(), dir_);
  EXPECT_TRUE(std::filesystem::exists(dir_ / "tessera.db"));
  EXPECT_TRUE(std::filesystem::is_directory(dir_ / "images"));
  SqliteDb db(dir_ / "tessera.db");
  EXPECT_EQ(db.query_text("PRAGMA journal_mode"), "wal");
  EXPECT_EQ(db.query_text("PRAGMA user_version"), "3");
}

TEST_F(StoreTest, RefusesADatabaseFromANewerVersion) {
  store_.reset();
  SqliteDb(dir_ / "tessera.db").exec("PRAGMA user_version=99");
  try {
    Store store(dir_);
    FAIL() << "opened a database of schema version 99";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("schema version 99"), std::string::npos) << e.what();
  }
}

TEST_F(StoreTest, UpgradesAVersion1DatabaseKeepingItsRows) {
  store_->insert_job(job_row("j-1", "d1"), R"({"scene":1})", tile_rows("j-1"));
  store_.reset();
  {  // what version 1 wrote: tiles without last_error, with their pixels in the row
    SqliteDb db(dir_ / "tessera.db");
    make_version_2(db);
    db.exec("ALTER TABLE tiles DROP COLUMN last_error");
    db.exec("PRAGMA user_version=1");
  }
  store_ = std::make_unique<Store>(dir_);
  EXPECT_EQ(SqliteDb(dir_ / "tessera.db").query_text("PRAGMA user_version"), "3");
  TileRow failed = tile_rows("j-1")[0];
  failed.attempts = 1;
  failed.last_error = "it broke";
  store_->update_tile(failed);
  const StoredState state = store_->load();
  ASSERT_EQ(state.jobs.size(), 1u);
  ASSERT_EQ(state.tiles.size(), tile_rows("j-1").size());
  EXPECT_EQ(state.tiles[0].last_error, "it broke");
  EXPECT_EQ(state.tiles[1].last_error, "");
}

TEST_F(StoreTest, UpgradesAVersion2DatabaseMovingThePixelsOutOfTheTileRows) {
  store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));
  store_.reset();
  const std::vector<float> pixels(20 * 20 * 3, 0.25f);
  {  // what version 2 wrote: tile 1 done, its pixels in its row
    SqliteDb db(dir_ / "tessera.db");
    make_version_2(db);
    db.statement("UPDATE tiles SET state = 'done', pixels = ? WHERE tile_index = 1")
        ->bind_blob(1, std::as_bytes(std::span(pixels)))
        .run();
  }
  store_ = std::make_unique<Store>(dir_);
  SqliteDb db(dir_ / "tessera.db");
  EXPECT_EQ(db.query_text("PRAGMA user_version"), "3");
  EXPECT_EQ(db.query_text("SELECT count(*) FROM pragma_table_info('tiles') WHERE name = 'pixels'"), "0");
  const StoredState state = store_->load();
  ASSERT_EQ(state.tiles.size(), 2u);
  EXPECT_EQ(state.tiles[0].pixel_bytes, 0);
  EXPECT_EQ(state.tiles[1].pixel_bytes, static_cast<std::int64_t>(pixels.size() * 4));
  expect_only_pixels_of_tile_1(*store_, pixels);
}

TEST_F(StoreTest, PixelsStoredAgainReplaceTheOldAndGoWithTheirJob) {
  store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));
  store_->insert_job(job_row("j-2", "d1"), "{}", tile_rows("j-2"));
  TileRow done = tile_rows("j-1")[0];
  done.state = "done";
  store_->store_tile_result(done, std::vector<float>(20 * 20 * 3, 1.0f));
  store_->store_tile_result(done, std::vector<float>(20 * 20 * 3, 2.0f));  // rendered again
  TileRow other = tile_rows("j-2")[1];
  other.state = "done";
  store_->store_tile_result(other, std::vector<float>(20 * 20 * 3, 3.0f));
  SqliteDb db(dir_ / "tessera.db");
  EXPECT_EQ(db.query_text("SELECT count(*) FROM tile_pixels"), "2");
  store_->for_each_tile_pixels("j-1", [&](int index, std::span<const float> stored) {
    EXPECT_EQ(index, 0);
    EXPECT_EQ(stored[0], 2.0f);
  });
  // A state change without pixels keeps them.
  done.state = "pending";
  store_->update_tile(done);
  EXPECT_EQ(db.query_text("SELECT count(*) FROM tile_pixels"), "2");
  store_->delete_job("j-1");
  EXPECT_EQ(db.query_text("SELECT count(*) FROM tile_pixels"), "1");
}

TEST_F(StoreTest, TilesAreStoredInTheOrderGivenAndLoadedByIndex) {
  // The Scheduler gives them in hand-out order, so that a lease's rows lie together.
  std::vector<TileRow> tiles = tile_rows("j-1");
  std::swap(tiles[0], tiles[1]);
  store_->insert_job(job_row("j-1", "d1"), "{}", tiles);
  SqliteDb db(dir_ / "tessera.db");
  EXPECT_EQ(db.query_text("SELECT tile_index FROM tiles ORDER BY rowid LIMIT 1"), "1");
  const StoredState state = store_->load();
  ASSERT_EQ(state.tiles.size(), 2u);
  EXPECT_EQ(state.tiles[0].tile_index, 0);
  EXPECT_EQ(state.tiles[1].tile_index, 1);
}

TEST_F(StoreTest, TheWalIsCheckpointedWhileTheStoreWrites) {
  store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));
  // More than a thousand pages of pixels: the store's own commits do not checkpoint (its
  // automatic checkpoint is off), its checkpointer thread does, so the database file
  // grows before the store is closed.
  const std::vector<float> pixels(20 * 20 * 3, 0.5f);
  for (int round = 0; round < 400; ++round) {
    TileRow done = tile_rows("j-1")[round % 2];
    done.state = "done";
    done.rays = static_cast<std::uint64_t>(round);
    store_->store_tile_result(done, pixels);
  }
  const auto db_size = [&] { return std::filesystem::file_size(dir_ / "tessera.db"); };
  const auto start = std::chrono::steady_clock::now();
  while (db_size() < 4096 * 4 && std::chrono::steady_clock::now() - start < std::chrono::seconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_GE(db_size(), 4096u * 4) << "nothing was checkpointed into the database file";
  reopen();
  EXPECT_EQ(store_->load().tiles[1].rays, 399u);
}

TEST_F(StoreTest, JobsTilesScenesAndWorkersSurviveAReopen) {
  store_->insert_job(job_row("j-1", "d1"), R"({"scene":1})", tile_rows("j-1"));
  TileRow leased = tile_rows("j-1")[1];
  leased.state = "leased";
  leased.lease_id = "l-1";
  leased.worker_id = "w-1";
  leased.lease_expires_ms = 99;
  leased.attempts = 2;
  store_->update_tile(leased);
  JobRow running = job_row("j-1", "d1");
  running.state = "running";
  running.started_at_ms = 1300;
  running.rays = (std::uint64_t{1} << 40) + 3;  // beyond 32 bits
  store_->update_job(running);
  WorkerRow worker{"w-1", "box", "10.0.0.2", 16, "rendering", 5, 2000};
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
  EXPECT_EQ(state.jobs[0].started_at_ms, 1300);
  EXPECT_EQ(state.jobs[0].rays, (std::uint64_t{1} << 40) + 3);
  ASSERT_EQ(state.tiles.size(), 2u);
  EXPECT_EQ(state.tiles[0].state, "pending");
  EXPECT_EQ(state.tiles[0].pixel_bytes, 0);
  EXPECT_EQ(state.tiles[1].rect, (TileRect{20, 0, 20, 20}));
  EXPECT_EQ(state.tiles[1].lease_id, "l-1");
  EXPECT_EQ(state.tiles[1].worker_id, "w-1");
  EXPECT_EQ(state.tiles[1].lease_expires_ms, 99);
  EXPECT_EQ(state.tiles[1].attempts, 2);
  ASSERT_EQ(state.workers.size(), 1u);
  EXPECT_EQ(state.workers[0].host, "10.0.0.2");
  EXPECT_EQ(state.workers[0].threads, 16);
  EXPECT_EQ(state.workers[0].state, "idle");
  EXPECT_EQ(state.workers[0].tiles_rendered, 6u);
  EXPECT_EQ(state.workers[0].last_seen_ms, 2500);
  EXPECT_EQ(store_->scene_json("d1"), R"({"scene":1})");
  EXPECT_FALSE(store_->scene_json("d2"));
}

TEST_F(StoreTest, TilePixelsAreStoredExactlyWithTheirState) {
  store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));
  std::vector<float> pixels(20 * 20 * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i)
    pixels[i] = static_cast<float>(i) * -0.1f + 1e-40f;  // includes a denormal
  TileRow done = tile_rows("j-1")[1];
  done.state = "done";
  done.rays = 77;
  done.result_lease_id = "l-9";
  store_->store_tile_result(done, pixels);

  reopen();
  const StoredState state = store_->load();
  EXPECT_EQ(state.tiles[1].state, "done");
  EXPECT_EQ(state.tiles[1].rays, 77u);
  EXPECT_EQ(state.tiles[1].result_lease_id, "l-9");
  EXPECT_EQ(state.tiles[1].pixel_bytes, static_cast<std::int64_t>(pixels.size() * 4));
  expect_only_pixels_of_tile_1(*store_, pixels);
}

TEST_F(StoreTest, DeleteJobTakesTilesImageAndOrphanedSceneOnly) {
  store_->insert_job(job_row("j-1", "shared"), "{}", tile_rows("j-1"));
  store_->insert_job(job_row("j-2", "shared"), "{}", tile_rows("j-2"));
  store_->insert_job(job_row("j-3", "own"), "{}", tile_rows("j-3"));
  store_->write_image("j-1", Image(4, 4));
  EXPECT_TRUE(store_->has_image("j-1"));

  store_->delete_job("j-1");
  EXPECT_FALSE(store_->has_image("j-1"));
  EXPECT_TRUE(store_->scene_json("shared"));
  store_->delete_job("j-3");
  EXPECT_FALSE(store_->scene_json("own"));
  const StoredState state = store_->load();
  ASSERT_EQ(state.jobs.size(), 1u);
  EXPECT_EQ(state.jobs[0].id, "j-2");
  EXPECT_EQ(state.tiles.size(), 2u);
}

TEST_F(StoreTest, TransactionsRollBackUnlessCommitted) {
  {
    Transaction tx = store_->transaction();
    store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));  // nested
  }
  EXPECT_TRUE(store_->load().jobs.empty());
  EXPECT_FALSE(store_->scene_json("d1"));
  {
    Transaction tx = store_->transaction();
    store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));
    tx.commit();
  }
  EXPECT_EQ(store_->load().jobs.size(), 1u);
}

TEST_F(StoreTest, FailuresNameTheOperationAndSqlitesMessage) {
  store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));
  try {
    store_->insert_job(job_row("j-1", "d1"), "{}", tile_rows("j-1"));
    FAIL() << "inserted a job twice";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("UNIQUE constraint failed: jobs.id"), std::string::npos) << message;
    EXPECT_NE(message.find("INSERT INTO jobs"), std::string::npos) << message;
  }
  // The failed insert left nothing behind, and the store still works.
  EXPECT_EQ(store_->load().tiles.size(), 2u);
  store_->update_job(job_row("j-1", "d1"));
}

TEST_F(StoreTest, PruneImagesDeletesUnkeptImagesAndLeftovers) {
  store_->write_image("j-keep", Image(2, 2));
  store_->write_image("j-drop", Image(2, 2));
  std::ofstream(dir_ / "images" / ".j-keep.tmp123.exr") << "partial";
  std::ofstream(dir_ / "images" / "notes.txt") << "not ours";
  store_->prune_images([](const std::string& id) { return id == "j-keep"; });
  EXPECT_TRUE(store_->has_image("j-keep"));
  EXPECT_FALSE(store_->has_image("j-drop"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "images" / ".j-keep.tmp123.exr"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "images" / "notes.txt"));
}

}  // namespace
}  // namespace tessera
