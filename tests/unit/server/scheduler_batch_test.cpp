// Leases on batches of tiles: how a claim sizes its batch, how the tiles of one lease are
// delivered in groups, and what happens to the ones still owed when the lease ends early.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "server/farm/sqlite_db.hpp"
#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using namespace test;

// The lease's tiles after the first.
std::vector<int> rest_of(const LeaseRecord& lease) {
  std::vector<int> indexes = indexes_of(lease);
  indexes.erase(indexes.begin());
  return indexes;
}

class SchedulerBatchTest : public SchedulerTest {
 protected:
  // Delivers the lease's first tile alone, as a group of one.
  ResultOutcome deliver_first(const LeaseRecord& lease) {
    const std::vector<float> pixels = tile_pixels(lease.tiles[0].rect, 1.0f);
    const std::vector<TileResult> group{{lease.tiles[0].index, pixels, 10}};
    return s().complete(lease.id, group);
  }
};

TEST_F(SchedulerBatchTest, AClaimTakesUpToHalfOfTheWorkersShareCentreFirst) {
  const std::string job = submit(96, 96, 32).id;  // 3x3 tiles, centre-first 4 1 3 5 7 0 2 6 8
  const std::string w = worker();
  const LeaseRecord first = *s().claim(w, 100);
  EXPECT_EQ(indexes_of(first), (std::vector<int>{4, 1, 3, 5}));  // 9 pending / 2
  EXPECT_EQ(s().job(job)->tiles_rendering, 4);
  EXPECT_EQ(info_of(w).current_tile, 4);
  ASSERT_EQ(deliver(first), ResultOutcome::accepted);  // all four, in the lease's order
  EXPECT_EQ(s().job(job)->tiles_done, 4);
  EXPECT_EQ(info_of(w).state, WorkerState::idle);
  EXPECT_EQ(info_of(w).tiles_rendered, 4u);

  // The batch shrinks as the job nears its end, down to single tiles.
  EXPECT_EQ(indexes_of(*s().claim(w, 100)), (std::vector<int>{7, 0}));
}

TEST_F(SchedulerBatchTest, EveryWorkerIsCountedInTheShareAndMaxTilesCaps) {
  submit(128, 128, 16);  // 64 tiles
  const std::string w1 = worker("one");
  const std::string w2 = worker("two");
  EXPECT_EQ(s().claim(w1, 100)->tiles.size(), 16u);  // 64 / (2 * 2)
  EXPECT_EQ(s().claim(w2, 5)->tiles.size(), 5u);
  const std::string w3 = worker("three");
  s().worker_left(w3);                                          // a worker that left takes no share
  EXPECT_EQ(s().claim(worker("four"), 100)->tiles.size(), 7u);  // 43 / (2 * 3)
}

TEST_F(SchedulerBatchTest, TilesOfOneLeaseAreDeliveredInGroups) {
  const std::string job = submit(96, 96, 32).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 100);
  ASSERT_EQ(lease.tiles.size(), 4u);
  const LeaseTileRecord& a = lease.tiles[0];
  const LeaseTileRecord& b = lease.tiles[1];
  const LeaseTileRecord& c = lease.tiles[2];
  const LeaseTileRecord& d = lease.tiles[3];
  const auto pixels_a = tile_pixels(a.rect, 1.0f);
  const auto pixels_b = tile_pixels(b.rect, 2.0f);
  const auto pixels_c = tile_pixels(c.rect, 3.0f);
  const auto pixels_d = tile_pixels(d.rect, 4.0f);
  const auto other_b = tile_pixels(b.rect, 9.0f);

  const std::vector<TileResult> group{{b.index, pixels_b, 20}, {a.index, pixels_a, 10}};
  ASSERT_EQ(s().complete(lease.id, group), ResultOutcome::accepted);
  EXPECT_EQ(s().job(job)->tiles_done, 2);
  EXPECT_EQ(s().job(job)->tiles_rendering, 2);
  EXPECT_EQ(s().job(job)->rays, 30u);
  EXPECT_EQ(info_of(w).current_tile, c.index);  // the next one owed
  EXPECT_EQ(info_of(w).tiles_rendered, 2u);
  const auto owed = s().heartbeat(lease.id);
  ASSERT_TRUE(owed);
  EXPECT_EQ(indexes_of(*owed), (std::vector<int>{c.index, d.index}));
  EXPECT_EQ(s().claim(w, 100)->id, lease.id);  // a re-claim gets what is still owed

  // A repeat alone is a duplicate; beside a new tile it is ignored. Either way the first
  // accepted pixels stay.
  const std::vector<TileResult> repeat{{b.index, other_b, 20}};
  EXPECT_EQ(s().complete(lease.id, repeat), ResultOutcome::duplicate);
  const std::vector<TileResult> mixed{{b.index, other_b, 20}, {c.index, pixels_c, 30}};
  EXPECT_EQ(s().complete(lease.id, mixed), ResultOutcome::accepted);
  EXPECT_EQ(s().job(job)->rays, 60u);
  const std::vector<TileResult> last{{d.index, pixels_d, 40}};
  EXPECT_EQ(s().complete(lease.id, last), ResultOutcome::accepted);
  EXPECT_EQ(info_of(w).state, WorkerState::idle);
  EXPECT_FALSE(s().heartbeat(lease.id));  // nothing owed: the lease is over
  EXPECT_EQ(s().complete(lease.id, repeat), ResultOutcome::duplicate);

  Image expected(96, 96);
  expected.paste(a.rect, pixels_a);
  expected.paste(b.rect, pixels_b);
  expected.paste(c.rect, pixels_c);
  expected.paste(d.rect, pixels_d);
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), expected.pixels()));
  reopen();  // the store knows which lease delivered what
  EXPECT_EQ(s().complete(lease.id, repeat), ResultOutcome::duplicate);
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), expected.pixels()));
}

TEST_F(SchedulerBatchTest, AnUploadIsAllOrNothing) {
  const std::string job = submit(96, 96, 32).id;
  const LeaseRecord lease = *s().claim(worker(), 100);
  const LeaseTileRecord& a = lease.tiles[0];
  const LeaseTileRecord& b = lease.tiles[1];
  const auto pixels_a = tile_pixels(a.rect, 1.0f);
  const auto pixels_b = tile_pixels(b.rect, 2.0f);
  auto short_b = pixels_b;
  short_b.pop_back();
  const int foreign = 0;  // a tile of the job that this lease does not hold
  const std::vector<int> held = indexes_of(lease);
  ASSERT_EQ(std::count(held.begin(), held.end(), foreign), 0);
  const auto pixels_foreign = tile_pixels(split_into_tiles(96, 96, 32)[foreign], 5.0f);

  const std::vector<TileResult> with_foreign{{a.index, pixels_a, 1}, {foreign, pixels_foreign, 1}};
  EXPECT_EQ(s().complete(lease.id, with_foreign), ResultOutcome::wrong_tile);
  const std::vector<TileResult> twice{{a.index, pixels_a, 1}, {a.index, pixels_a, 1}};
  EXPECT_EQ(s().complete(lease.id, twice), ResultOutcome::wrong_tile);
  const std::vector<TileResult> with_short{{a.index, pixels_a, 1}, {b.index, short_b, 1}};
  EXPECT_EQ(s().complete(lease.id, with_short), ResultOutcome::wrong_size);
  // The whole-lease form wants every owed tile, no more and no less.
  EXPECT_EQ(s().complete(lease.id, pixels_a, 1), ResultOutcome::wrong_size);
  EXPECT_EQ(s().job(job)->tiles_done, 0);
  EXPECT_EQ(s().job(job)->tiles_rendering, 4);
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), Image(96, 96).pixels()));
}

TEST_F(SchedulerBatchTest, AnExpiredBatchReturnsOnlyTheTilesStillOwed) {
  const std::string job = submit(96, 96, 32).id;
  const std::string slow = worker("slow");
  const LeaseRecord lease = *s().claim(slow, 100);
  ASSERT_EQ(deliver_first(lease), ResultOutcome::accepted);

  clock_.advance_ms(timeout_ms);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_done, 1);
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);
  EXPECT_EQ(info_of(slow).state, WorkerState::idle);
  EXPECT_FALSE(s().heartbeat(lease.id));

  // The owed tiles go out again first, under a new lease. The expiry counted against each
  // of them (the worker has 4 threads, so it may have been on any of the 3), and a tile
  // that failed goes out alone.
  const LeaseRecord rescue = *s().claim(worker("rescuer"), 3);
  EXPECT_NE(rescue.id, lease.id);
  EXPECT_EQ(indexes_of(rescue), (std::vector<int>{rest_of(lease).front()}));
  // The old lease: its delivered tile is a duplicate, an owed one stale.
  const auto late_b = tile_pixels(lease.tiles[1].rect, 9.0f);
  const std::vector<TileResult> late{{lease.tiles[1].index, late_b, 10}};
  EXPECT_EQ(s().complete(lease.id, late), ResultOutcome::stale);
  EXPECT_EQ(deliver_first(lease), ResultOutcome::duplicate);
  ASSERT_EQ(deliver(rescue, 2.0f), ResultOutcome::accepted);
  EXPECT_EQ(s().job(job)->tiles_done, 2);
}

TEST_F(SchedulerBatchTest, ReleaseGivesBackWhatWasNotDelivered) {
  const std::string job = submit(96, 96, 32).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 100);
  ASSERT_EQ(deliver_first(lease), ResultOutcome::accepted);
  s().release(lease.id);
  EXPECT_EQ(s().job(job)->tiles_done, 1);
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);
  EXPECT_EQ(info_of(w).state, WorkerState::idle);
  const LeaseRecord next = *s().claim(w, 100);
  EXPECT_NE(next.id, lease.id);
  EXPECT_EQ(next.tiles[0].index, lease.tiles[1].index);  // first in line again
}

TEST_F(SchedulerBatchTest, ARestartKeepsTheBatchLeaseForItsWorker) {
  const std::string job = submit(96, 96, 32).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 100);
  ASSERT_EQ(deliver_first(lease), ResultOutcome::accepted);
  reopen();
  EXPECT_EQ(info_of(w).state, WorkerState::rendering);
  EXPECT_EQ(info_of(w).current_tile, lease.tiles[1].index);
  const LeaseRecord back = *s().claim(w, 100);
  EXPECT_EQ(back.id, lease.id);
  EXPECT_EQ(indexes_of(back), rest_of(lease));
  EXPECT_EQ(s().job(job)->tiles_rendering, 3);
}

TEST_F(SchedulerBatchTest, AnExtensionAddsTheJobsNextTilesToTheLiveLeaseAndRenewsIt) {
  const std::string job = submit(96, 96, 32).id;  // centre-first 4 1 3 5 7 0 2 6 8
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 100);
  ASSERT_EQ(indexes_of(lease), (std::vector<int>{4, 1, 3, 5}));
  clock_.advance_ms(timeout_ms - 1);
  const auto added = s().extend(lease.id, 100);
  ASSERT_TRUE(added);
  EXPECT_EQ(added->id, lease.id);
  EXPECT_EQ(indexes_of(*added), (std::vector<int>{7, 0}));  // cut as a claim: 5 pending / 2
  EXPECT_EQ(s().job(job)->tiles_rendering, 6);
  clock_.advance_ms(2);  // past the claim's expiry, not the extension's
  s().expire_leases();
  const auto owed = s().heartbeat(lease.id);
  ASSERT_TRUE(owed);
  EXPECT_EQ(indexes_of(*owed), (std::vector<int>{4, 1, 3, 5, 7, 0}));
  EXPECT_EQ(indexes_of(*s().extend(lease.id, 1)), (std::vector<int>{2}));  // max_tiles caps
  ASSERT_EQ(deliver(*s().heartbeat(lease.id)), ResultOutcome::accepted);
  EXPECT_EQ(s().job(job)->tiles_done, 7);
  EXPECT_EQ(info_of(w).state, WorkerState::idle);
  EXPECT_FALSE(s().extend(lease.id, 100));  // the lease is over once it owes nothing
}

TEST_F(SchedulerBatchTest, AnExtensionAddsNothingWhileAJobOfHigherPriorityWaits) {
  submit(96, 96, 32, 50);
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 100);
  const std::string urgent = submit(64, 64, 32, 80).id;
  const auto added = s().extend(lease.id, 100);
  ASSERT_TRUE(added);
  EXPECT_TRUE(added->tiles.empty());
  EXPECT_EQ(s().heartbeat(lease.id)->tiles.size(), lease.tiles.size());  // goes on as it was
  ASSERT_EQ(deliver(lease), ResultOutcome::accepted);
  EXPECT_EQ(s().claim(w, 100)->job_id, urgent);
}

TEST_F(SchedulerBatchTest, AnExtensionStopsBeforeATileThatFailedBefore) {
  submit(96, 96, 32);
  const std::string w1 = worker("one");
  const std::string w2 = worker("two");
  const LeaseRecord first = *s().claim(w1, 1);
  const LeaseRecord second = *s().claim(w2, 1);
  ASSERT_EQ(indexes_of(second), (std::vector<int>{1}));
  s().fail_tile(second.id, 1, "out of memory");  // tile 1 is next in line, and failed once
  EXPECT_TRUE(s().extend(first.id, 100)->tiles.empty());
  EXPECT_EQ(indexes_of(*s().claim(w2, 100)), (std::vector<int>{1}));  // alone
  // The next in line again, cut as a claim would be: 7 pending / (2 * 2).
  EXPECT_EQ(indexes_of(*s().extend(first.id, 100)), (std::vector<int>{3}));
}

TEST_F(SchedulerBatchTest, AJobWhoseImageCannotBeWrittenFails) {
  const std::string job = submit(32, 32, 32).id;
  // A file where the images directory should be: the image write must fail.
  std::filesystem::remove_all(store_->data_dir() / "images");
  std::ofstream(store_->data_dir() / "images") << "not a directory";
  ASSERT_EQ(deliver(*s().claim(worker())), ResultOutcome::accepted);
  s().wait_for_images();
  const JobRecord failed = *s().job(job);
  EXPECT_EQ(failed.state, JobState::failed);
  EXPECT_NE(failed.error.find("cannot write the image"), std::string::npos) << failed.error;
  EXPECT_EQ(failed.tiles_done, 1);  // the tiles are kept all the same
  EXPECT_FALSE(s().image_file(job));
}

// The disk was full when the image was written, and has room again: a retry writes it
// from the stored tiles, rendering nothing again, and the job is completed for good.
TEST_F(SchedulerBatchTest, ARetryWritesTheImageThatCouldNotBeWritten) {
  const std::string job = submit(64, 32, 16).id;  // 8 tiles
  std::filesystem::remove_all(store_->data_dir() / "images");
  std::ofstream(store_->data_dir() / "images") << "not a directory";
  const std::string w = worker();
  while (const auto lease = s().claim(w, 100))
    ASSERT_EQ(deliver(*lease, 0.25f), ResultOutcome::accepted);
  s().wait_for_images();
  ASSERT_EQ(s().job(job)->state, JobState::failed);
  // Still no room: the retry is taken, and fails again for the same reason.
  ASSERT_EQ(s().retry(job).result, ControlOutcome::Result::done);
  s().wait_for_images();
  EXPECT_EQ(s().job(job)->state, JobState::failed);
  EXPECT_NE(s().job(job)->error.find("cannot write the image"), std::string::npos);

  std::filesystem::remove(store_->data_dir() / "images");
  std::filesystem::create_directories(store_->data_dir() / "images");
  ASSERT_EQ(s().retry(job).result, ControlOutcome::Result::done);
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  EXPECT_EQ(s().job(job)->error, "");
  EXPECT_FALSE(s().claim(w, 100)) << "nothing renders again";
  s().wait_for_images();
  Image expected(64, 32);
  for (const TileRect& rect : split_into_tiles(64, 32, 16))
    expected.paste(rect, tile_pixels(rect, 0.25f));
  ASSERT_TRUE(s().image_file(job));
  EXPECT_TRUE(same_bits(read_image(*s().image_file(job)).pixels(), expected.pixels()));
  reopen();
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  ASSERT_TRUE(s().image_file(job));
  EXPECT_EQ(s().retry(job).code, "not_failed");
}

// What the store writes per operation: a row per lease and per upload, whatever the tiles.
TEST_F(SqliteSchedulerTest, AnUploadIsStoredAsOneRowAndALeaseAsAnother) {
  const std::string job = submit(96, 96, 8).id;  // 144 tiles
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 16);
  ASSERT_EQ(lease.tiles.size(), 16u);
  const LeaseRecord added = *s().extend(lease.id, 16);
  ASSERT_EQ(added.tiles.size(), 16u);
  const auto count = [&](const char* table) {
    return SqliteDb(store_->data_dir() / "tessera.db")
        .query_text(std::string("SELECT count(*) FROM ") + table);
  };
  EXPECT_EQ(count("leases"), "1");
  EXPECT_EQ(count("results"), "0");
  ASSERT_EQ(s().complete(lease.id, std::span<const float>(), 0), ResultOutcome::wrong_size);

  // The first 16 in one upload.
  std::vector<std::vector<float>> pixels;
  std::vector<TileResult> group;
  for (const LeaseTileRecord& tile : lease.tiles) pixels.push_back(tile_pixels(tile.rect, 1.0f));
  for (std::size_t i = 0; i < lease.tiles.size(); ++i)
    group.push_back({lease.tiles[i].index, pixels[i], 10});
  ASSERT_EQ(s().complete(lease.id, group), ResultOutcome::accepted);
  EXPECT_EQ(count("results"), "1");
  EXPECT_EQ(count("leases"), "1");

  // A restart finds the 16 done and the lease owing the other 16.
  reopen();
  EXPECT_EQ(s().job(job)->tiles_done, 16);
  EXPECT_EQ(s().job(job)->rays, 160u);
  const LeaseRecord back = *s().claim(w, 16);
  EXPECT_EQ(back.id, lease.id);
  EXPECT_EQ(indexes_of(back), indexes_of(added));
  ASSERT_EQ(deliver(back), ResultOutcome::accepted);
  EXPECT_EQ(count("results"), "2");
  EXPECT_EQ(count("leases"), "0");  // it owes nothing more
  EXPECT_EQ(count("tile_failures"), "0");

  finish(job, w);
  s().wait_for_images();
  Image expected(96, 96);
  for (const TileRect& rect : split_into_tiles(96, 96, 8))
    expected.paste(rect, tile_pixels(rect, 0.0f));
  for (std::size_t i = 0; i < lease.tiles.size(); ++i)
    expected.paste(lease.tiles[i].rect, pixels[i]);
  EXPECT_TRUE(
      same_bits(read_image(ImageFiles(store_->data_dir()).path(job)).pixels(), expected.pixels()));
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), expected.pixels()));
}

TEST_F(SqliteSchedulerTest, ARestartForgetsAResultWhosePixelsAreCutShortAndRendersItsTilesAgain) {
  const std::string job = submit(96, 96, 32).id;
  const std::string w = worker();
  const LeaseRecord first = *s().claim(w, 100);  // 4 1 3 5
  ASSERT_EQ(deliver(first, 0.0f, 40), ResultOutcome::accepted);
  const LeaseRecord second = *s().claim(w, 2);  // 7 0
  ASSERT_EQ(deliver(second, 0.0f, 20), ResultOutcome::accepted);
  ASSERT_EQ(s().job(job)->rays, 60u);
  scheduler_.reset();
  // What a power loss may leave: the rows of both uploads, the pixels of the first only
  // and of the second in part.
  const std::filesystem::path pixels = sqlite().pixel_path(job);
  store_.reset();
  ASSERT_EQ(std::filesystem::file_size(pixels), 6u * 32 * 32 * 12);
  std::filesystem::resize_file(pixels, 5u * 32 * 32 * 12 + 100);
  open();
  const JobRecord after = *s().job(job);
  EXPECT_EQ(after.tiles_done, 4);
  EXPECT_EQ(after.rays, 40u);
  EXPECT_EQ(SqliteDb(dir_ / "tessera.db").query_text("SELECT count(*) FROM results"), "1");
  reopen();  // what the first start decided was stored
  EXPECT_EQ(s().job(job)->rays, 40u);
  EXPECT_EQ(s().job(job)->tiles_done, 4);
  const LeaseRecord again = *s().claim(w, 100);
  EXPECT_EQ(indexes_of(again), (std::vector<int>{7, 0}));  // 5 pending, cut to 5 / 2
  finish(job, w);
  s().wait_for_images();
  Image expected(96, 96);
  for (const TileRect& rect : split_into_tiles(96, 96, 32))
    expected.paste(rect, tile_pixels(rect, 0.0f));
  EXPECT_TRUE(
      same_bits(read_image(ImageFiles(store_->data_dir()).path(job)).pixels(), expected.pixels()));
}

}  // namespace
}  // namespace tessera
