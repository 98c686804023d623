// What keeps a job from stalling unseen: the limits on hand-outs and on time without
// progress, the lease size an extension may reach, and the signs of trouble a job shows
// before any of them ends it.
#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using test::SchedulerTest;

// 4x4 tiles of 8 px.
constexpr int kSize = 32;
constexpr int kTile = 8;

TEST_F(SchedulerTest, ARefusedResultShowsOnItsJob) {
  const JobRecord job = submit(kSize, kSize, kTile);
  const std::string w = worker();
  const auto lease = s().claim(w, 4);
  ASSERT_TRUE(lease);
  EXPECT_EQ(s().job(job.id)->health.refused_results, 0);
  EXPECT_TRUE(s().job(job.id)->health.last_problem.empty());

  s().note_refused_result(lease->id, "413: a result carries at most 256 tiles; this one has 1,365");
  const JobHealthRecord health = s().job(job.id)->health;
  EXPECT_EQ(health.refused_results, 1);
  EXPECT_NE(health.last_problem.find("this one has 1,365"), std::string::npos)
      << health.last_problem;
  EXPECT_EQ(s().job(job.id)->state, JobState::running);  // shown, not yet failed

  // The worker then reports the tile as failed: counted, and the job goes on.
  s().fail_tile(lease->id, lease->tiles.front().index, "the coordinator refused a result");
  EXPECT_EQ(s().job(job.id)->health.tile_failures, 1);
  EXPECT_NE(s().job(job.id)->health.last_problem.find("refused"), std::string::npos);
}

TEST_F(SchedulerTest, ATileHandedOutTooOftenFailsItsJobSayingSo) {
  config_.max_tile_handouts = 3;
  reopen();
  const JobRecord job = submit(kSize, kSize, kTile);
  const std::string w = worker();
  // Given back unrendered each time (a release charges no failure), as a worker that keeps
  // dropping its tiles would.
  for (int round = 1; round <= 3; ++round) {
    const auto lease = s().claim(w, 1);
    ASSERT_TRUE(lease) << round;
    if (round > 1) {
      EXPECT_EQ(s().job(job.id)->health.repeated_handouts, round - 1);
    }
    s().release(lease->id);
  }
  const auto failed = s().job(job.id);
  EXPECT_EQ(failed->state, JobState::failed);
  EXPECT_NE(failed->error.find("went out to workers 3 times without its result being accepted"),
            std::string::npos)
      << failed->error;
  EXPECT_FALSE(s().claim(w, 1));
}

TEST_F(SchedulerTest, AWorkerThatKeepsClaimingItsOwnLeaseBackEndsAtTheLimit) {
  config_.max_tile_handouts = 4;
  reopen();
  const JobRecord job = submit(kSize, kSize, kTile);
  const std::string w = worker();
  const auto first = s().claim(w, 2);
  ASSERT_TRUE(first);
  // The loop of issue 29: each claim hands the same lease back to be rendered again.
  for (int again = 2; again <= 4; ++again) {
    const auto same = s().claim(w, 2);
    ASSERT_TRUE(same) << again;
    EXPECT_EQ(same->id, first->id);
  }
  EXPECT_EQ(s().job(job.id)->health.repeated_handouts, 2 * 3);
  EXPECT_FALSE(s().claim(w, 2));  // a fifth time is one too many
  const auto failed = s().job(job.id);
  EXPECT_EQ(failed->state, JobState::failed);
  EXPECT_NE(failed->error.find("went out to workers 4 times"), std::string::npos) << failed->error;
  EXPECT_EQ(failed->tiles_rendering, 0);
}

TEST_F(SchedulerTest, AJobThatDeliversNothingWhileRenderingFailsAfterTheStallTimeout) {
  config_.stall_timeout_ms = 600'000;  // longer than the lease timeout: heartbeats keep it
  reopen();
  const JobRecord job = submit(kSize, kSize, kTile);
  const std::string w = worker();
  const auto lease = s().claim(w, 4);
  ASSERT_TRUE(lease);
  ASSERT_EQ(deliver(*lease), ResultOutcome::accepted);  // progress
  const auto stuck = s().claim(w, 4);
  ASSERT_TRUE(stuck);
  for (int step = 0; step < 59; ++step) {  // 590 s of heartbeats and no result
    clock_.advance_ms(10'000);
    ASSERT_TRUE(s().heartbeat(stuck->id));
    s().expire_leases();
  }
  EXPECT_EQ(s().job(job.id)->state, JobState::running);
  clock_.advance_ms(10'000);
  ASSERT_TRUE(s().heartbeat(stuck->id));
  s().expire_leases();
  const auto failed = s().job(job.id);
  EXPECT_EQ(failed->state, JobState::failed);
  EXPECT_NE(failed->error.find("no tile was delivered for 600 s"), std::string::npos)
      << failed->error;
  EXPECT_FALSE(s().heartbeat(stuck->id));  // its tiles are withdrawn
}

TEST_F(SchedulerTest, AJobWaitingForWorkersIsNotStalled) {
  config_.stall_timeout_ms = 60'000;
  reopen();
  const JobRecord job = submit(kSize, kSize, kTile);
  // Nothing under lease for ten minutes: no workers, which is not the job's fault.
  clock_.advance_ms(600'000);
  s().expire_leases();
  EXPECT_EQ(s().job(job.id)->state, JobState::queued);
  // Once rendering starts, the stall clock starts from then, not from submission.
  const std::string w = worker();
  const auto lease = s().claim(w, 1);
  ASSERT_TRUE(lease);
  clock_.advance_ms(20'000);
  s().expire_leases();
  EXPECT_EQ(s().job(job.id)->state, JobState::running);
  ASSERT_EQ(deliver(*lease), ResultOutcome::accepted);
}

TEST_F(SchedulerTest, ExtensionsNeverGrowALeasePastTheLeaseLimit) {
  config_.max_lease_tiles = 6;
  reopen();
  const JobRecord job = submit(64, 64, kTile);  // 64 tiles
  const std::string w = worker();
  const auto lease = s().claim(w, 4);
  ASSERT_TRUE(lease);
  ASSERT_EQ(lease->tiles.size(), 4u);
  const auto more = s().extend(lease->id, 4);
  ASSERT_TRUE(more);
  EXPECT_EQ(more->tiles.size(), 2u);  // to 6, not 8
  const auto none = s().extend(lease->id, 4);
  ASSERT_TRUE(none);
  EXPECT_TRUE(none->tiles.empty());
  EXPECT_EQ(s().heartbeat(lease->id)->tiles.size(), 6u);
  EXPECT_EQ(s().job(job.id)->tiles_rendering, 6);
}

TEST_F(SchedulerTest, TileFailuresAreRecountedFromTheStoreAfterARestart) {
  const JobRecord job = submit(kSize, kSize, kTile);
  const std::string w = worker();
  const auto lease = s().claim(w, 1);
  ASSERT_TRUE(lease);
  s().fail_tile(lease->id, lease->tiles.front().index, "out of memory");
  reopen();
  const JobHealthRecord health = s().job(job.id)->health;
  EXPECT_EQ(health.tile_failures, 1);
  EXPECT_NE(health.last_problem.find("out of memory"), std::string::npos) << health.last_problem;
}

}  // namespace
}  // namespace tessera
