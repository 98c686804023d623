// What keeps a claim cheap with a thousand workers and a million tiles: the count of
// workers that have not left (for the batch size), the live leases ordered by expiry (for
// reaping), and the pending tiles as a bit per hand-out position. Each must follow every
// change exactly as the full scans it replaced did.
#include <algorithm>
#include <set>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "server/farm/pending_tiles.hpp"
#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using namespace test;

TEST(PendingTilesTest, FindsTheFirstPendingPositionAcrossWordsAndAfterReinsertion) {
  PendingTiles pending;
  pending.reset(200);
  EXPECT_TRUE(pending.empty());
  EXPECT_EQ(pending.first_from(0), -1);
  for (const int position : {3, 64, 130, 199}) pending.insert(position);
  pending.insert(64);  // again: no change
  EXPECT_EQ(pending.size(), 4u);
  EXPECT_EQ(pending.first_from(0), 3);
  EXPECT_EQ(pending.first_from(4), 64);
  EXPECT_EQ(pending.first_from(65), 130);
  EXPECT_EQ(pending.first_from(131), 199);
  EXPECT_EQ(pending.first_from(200), -1);

  // Handed out from the front: the search moves on past the empty words...
  pending.erase(3);
  pending.erase(64);
  pending.erase(64);  // again: no change
  EXPECT_EQ(pending.size(), 2u);
  EXPECT_EQ(pending.first_from(0), 130);
  // ...and comes back when a tile returns to the queue before them.
  pending.insert(5);
  EXPECT_TRUE(pending.contains(5));
  EXPECT_FALSE(pending.contains(64));
  EXPECT_EQ(pending.first_from(0), 5);
  EXPECT_EQ(pending.first_from(6), 130);
  pending.erase(5);
  pending.erase(130);
  pending.erase(199);
  EXPECT_TRUE(pending.empty());
  EXPECT_EQ(pending.first_from(0), -1);
}

TEST_F(SchedulerTest, TheBatchShareCountsWorkersThatLeaveComeBackAndSurviveARestart) {
  submit(256, 256, 16);  // 256 tiles
  const std::string one = worker("one");
  const std::string two = worker("two");
  const std::string three = worker("three");
  EXPECT_EQ(s().claim(one, 256)->tiles.size(), 42u);  // 256 / (2 * 3)
  s().worker_left(two);
  s().worker_left(two);                                 // leaving twice counts once
  EXPECT_EQ(s().claim(three, 256)->tiles.size(), 53u);  // 214 / (2 * 2)
  s().touch_worker(two);                                // talking again: still left
  EXPECT_FALSE(s().claim(two, 256));                    // it registers again first
  const std::string back = worker("two");
  EXPECT_EQ(s().claim(back, 256)->tiles.size(), 26u);  // 161 / (2 * 3)

  // A restart forgets every worker without a lease until it talks again: here all three
  // hold one, so they stay, and a fourth that left before stays gone.
  const std::string four = worker("four");
  s().worker_left(four);
  reopen();
  const std::string five = worker("five");
  EXPECT_EQ(s().claim(five, 256)->tiles.size(), 16u);  // 135 / (2 * 4)
}

TEST_F(SchedulerTest, LeasesExpireInTheOrderOfTheirExpiryWhateverTheOrderOfTheirGrants) {
  const std::string job = submit(64, 64, 16).id;  // 16 tiles
  const std::string early = worker("early");
  const std::string late = worker("late");
  const LeaseRecord first = *s().claim(early);  // expires at timeout
  clock_.advance_ms(10'000);
  const LeaseRecord second = *s().claim(late);  // expires at 10 s + timeout
  clock_.advance_ms(5'000);
  ASSERT_TRUE(s().heartbeat(first.id));  // now expires at 15 s + timeout, after the second

  clock_.advance_ms(timeout_ms - 5'000);  // 10 s + timeout
  s().expire_leases();
  EXPECT_FALSE(s().heartbeat(second.id));
  EXPECT_EQ(info_of(late).state, WorkerState::idle);
  ASSERT_TRUE(s().heartbeat(first.id));  // 10 s + 2 * timeout now
  EXPECT_EQ(s().job(job)->tiles_rendering, 1);

  clock_.advance_ms(timeout_ms - 1);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_rendering, 1);
  clock_.advance_ms(1);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);
  EXPECT_FALSE(s().heartbeat(first.id));
}

TEST_F(SchedulerTest, ALeaseDeliveredInPartExpiresWithWhatItStillOwesAndKnowsWhatItDelivered) {
  const std::string job = submit(64, 64, 16).id;  // 16 tiles
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 4);
  ASSERT_EQ(lease.tiles.size(), 4u);
  const std::vector<float> pixels = tile_pixels(lease.tiles[0].rect, 1.0f);
  const std::vector<TileResult> first{{lease.tiles[0].index, pixels, 10}};
  ASSERT_EQ(s().complete(lease.id, first), ResultOutcome::accepted);

  clock_.advance_ms(timeout_ms);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);
  EXPECT_EQ(s().job(job)->tiles_done, 1);
  EXPECT_EQ(s().complete(lease.id, first), ResultOutcome::duplicate);
  const std::vector<float> other = tile_pixels(lease.tiles[1].rect, 1.0f);
  EXPECT_EQ(s().complete(lease.id, std::vector<TileResult>{{lease.tiles[1].index, other, 10}}),
            ResultOutcome::stale);
}

TEST_F(SchedulerTest, OfManyLeasesOnlyTheExpiredOnesAreReapedAndAfterARestartAllAtOnce) {
  const std::string job = submit(128, 128, 16).id;  // 64 tiles
  std::vector<LeaseRecord> leases;
  for (int i = 0; i < 20; ++i) {
    leases.push_back(*s().claim(worker("w" + std::to_string(i))));
    clock_.advance_ms(1'000);
  }
  // The lease granted at i seconds expires at i s + timeout; it is now 20 s.
  clock_.advance_ms(timeout_ms - 20'000 + 4'500);  // 4.5 s + timeout: leases 0 to 4 are due
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_rendering, 15);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(s().heartbeat(leases[i].id).has_value(), i >= 5) << i;

  // The others had their heartbeat just now; a restart gives them all a fresh timeout.
  reopen();
  clock_.advance_ms(timeout_ms - 1);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_rendering, 15);
  clock_.advance_ms(1);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);
}

TEST_F(SchedulerTest, ResultsAcceptedWhileTheCanvasIsMadeOutsideTheLockAreInTheImage) {
  // The first result makes the canvas with the lock released; the results that others
  // deliver meanwhile are only stored, and must come back from the store into the canvas.
  // The image file is written from the canvas, so a tile lost there shows in the file.
  const std::string job = submit(1024, 512, 16).id;  // 2048 tiles, a 6 MiB canvas
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, id = worker("w" + std::to_string(t))] {
      while (s().job(job)->state != JobState::completed)
        if (const auto lease = s().claim(id, 8)) deliver(*lease, 0.5f);
    });
  }
  for (std::thread& thread : threads) thread.join();
  s().wait_for_images();
  Image expected(1024, 512);
  for (const TileRect& rect : split_into_tiles(1024, 512, 16))
    expected.paste(rect, tile_pixels(rect, 0.5f));
  EXPECT_TRUE(
      same_bits(read_image(ImageFiles(store_->data_dir()).path(job)).pixels(), expected.pixels()));
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), expected.pixels()));
}

}  // namespace
}  // namespace tessera
