// Tiles that fail: retried up to a limit, then the job fails naming the tile; a failed
// tile goes out alone; a worker that keeps failing on a job is kept off it while another
// worker could take its tiles.
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using namespace test;

class SchedulerFailureTest : public SchedulerTest {
 protected:
  // Attempts of each tile of the one job of 9 tiles, as the store has them.
  std::vector<int> attempts() {
    std::vector<int> result(9, 0);
    for (const TileFailureRow& row : store_->load().failures)
      result.at(row.tile_index) = row.attempts;
    return result;
  }
};

TEST_F(SchedulerFailureTest, ATileThatKeepsFailingFailsItsJobNamingTheTileAndTheError) {
  const std::string job = submit(96, 96, 32).id;  // 9 tiles, tile 4 goes out first
  const std::string other = submit(32, 32, 32, 10).id;
  std::vector<std::string> workers{worker("a"), worker("b"), worker("c")};
  for (int attempt = 1; attempt <= 3; ++attempt) {
    const LeaseRecord lease = *s().claim(workers[attempt - 1], 4);
    ASSERT_EQ(lease.job_id, job);
    ASSERT_EQ(lease.tiles.front().index, 4);
    s().fail_tile(lease.id, 4, "out of memory, try " + std::to_string(attempt));
    EXPECT_FALSE(s().heartbeat(lease.id)) << "the failure ends the lease";
    if (attempt < 3) {
      EXPECT_EQ(s().job(job)->state, JobState::running);
    }
  }
  const JobRecord failed = *s().job(job);
  EXPECT_EQ(failed.state, JobState::failed);
  EXPECT_EQ(failed.error,
            "tile 4 at (32, 32) failed 3 times; the last error: out of memory, try 3");
  EXPECT_EQ(failed.finished_at_ms, clock_.now_ms());
  EXPECT_EQ(failed.tiles_rendering, 0);
  // The farm moves on to the next job.
  EXPECT_EQ(s().claim(workers[0])->job_id, other);
  reopen();  // and a restart does not bring the failed job back
  EXPECT_EQ(s().job(job)->state, JobState::failed);
  EXPECT_EQ(s().job(job)->error, failed.error);
}

TEST_F(SchedulerFailureTest, AFailureGivesTheLeasesOtherTilesBackUncharged) {
  submit(96, 96, 32);
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 4);
  ASSERT_EQ(lease.tiles.size(), 4u);
  s().fail_tile(lease.id, lease.tiles[1].index, "bad tile");
  std::vector<int> expected(9, 0);
  expected[lease.tiles[1].index] = 1;
  EXPECT_EQ(attempts(), expected);
  EXPECT_EQ(info_of(w).state, WorkerState::idle);
  s().fail_tile(lease.id, lease.tiles[2].index, "too late");  // the lease is over: nothing
  s().fail_tile("l-0000000000000000", 0, "unknown lease");
  EXPECT_EQ(attempts(), expected);
}

TEST_F(SchedulerFailureTest, AnExpiryChargesEveryTileStillOwedAndEachGoesOutAlone) {
  submit(96, 96, 32);  // centre-first: 4 1 3 5 7 0 2 6 8
  const std::string slow = worker("slow");
  const LeaseRecord lease = *s().claim(slow, 4);
  ASSERT_EQ(lease.tiles.size(), 4u);  // 4 1 3 5
  const std::vector<float> pixels = tile_pixels(lease.tiles[0].rect, 1.0f);
  const std::vector<TileResult> first{{4, pixels, 10}};
  ASSERT_EQ(s().complete(lease.id, first), ResultOutcome::accepted);
  clock_.advance_ms(timeout_ms);
  s().expire_leases();
  // Any of the three still owed may be the one it died on.
  std::vector<int> expected(9, 0);
  expected[1] = expected[3] = expected[5] = 1;
  EXPECT_EQ(attempts(), expected);
  // Each of them goes out alone; then batches again.
  const std::string next = worker("next");
  for (const int tile : {1, 3, 5}) {
    const LeaseRecord alone = *s().claim(next, 4);
    ASSERT_EQ(indexes_of(alone), std::vector<int>{tile});
    ASSERT_EQ(deliver(alone), ResultOutcome::accepted);
  }
  s().worker_left(slow);  // so that the next batch is not cut to a share of two workers
  EXPECT_EQ(s().claim(next, 2)->tiles.size(), 2u);
}

TEST_F(SchedulerFailureTest, AWorkerThatKeepsFailingIsKeptOffTheJobWhileOthersCanTakeIt) {
  SchedulerConfig config;
  config.max_tile_attempts = 10;  // the job itself must not fail here
  scheduler_.reset();
  scheduler_ = std::make_unique<Scheduler>(*store_, clock_, config);
  const std::string job = submit(96, 96, 32).id;
  const std::string flaky = worker("flaky");
  const std::string sound = worker("sound");
  for (int i = 0; i < 2; ++i) {
    const LeaseRecord lease = *s().claim(flaky);
    s().fail_tile(lease.id, lease.tiles[0].index, "flaky");
  }
  EXPECT_FALSE(s().claim(flaky)) << "a worker that failed twice on the job got it again";
  const auto taken = s().claim(sound);
  ASSERT_TRUE(taken);
  EXPECT_EQ(taken->job_id, job);
  // With nobody else left, the flaky worker is tried again rather than the job waiting.
  s().worker_left(sound);
  EXPECT_TRUE(s().claim(flaky));
}

}  // namespace
}  // namespace tessera
