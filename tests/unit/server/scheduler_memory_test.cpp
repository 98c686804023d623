// The jobs' tiles within the memory budget: what they hold is reckoned as jobs come and go,
// a job past the budget is refused saying so, and a start over the budget loads the oldest
// jobs that fit and fails the unfinished rest, which can then be removed.
#include <gtest/gtest.h>

#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using test::SchedulerTest;

class SchedulerMemoryTest : public SchedulerTest {
 protected:
  void with_budget(std::uint64_t tiles) {
    config_.job_memory_budget = tiles * kTileBytes;
    reopen();
  }
};

TEST_F(SchedulerMemoryTest, TheJobsTilesAreReckonedAsJobsComeAndGo) {
  with_budget(100);
  EXPECT_EQ(scheduler_->job_memory(), 0u);
  const std::string job = submit(64, 64, 8).id;  // 64 tiles
  EXPECT_EQ(scheduler_->job_memory(), 64 * kTileBytes);
  EXPECT_FALSE(scheduler_->job_memory_refusal(36));
  const std::optional<std::string> refusal = scheduler_->job_memory_refusal(37);
  ASSERT_TRUE(refusal);
  EXPECT_NE(refusal->find("--job-memory-budget"), std::string::npos) << *refusal;
  EXPECT_NE(refusal->find("37 tiles"), std::string::npos) << *refusal;
  s().cancel(job);
  EXPECT_EQ(s().remove(job), RemoveOutcome::removed);
  EXPECT_EQ(scheduler_->job_memory(), 0u);
  EXPECT_FALSE(scheduler_->job_memory_refusal(100));
}

TEST_F(SchedulerMemoryTest, AStartOverTheBudgetLoadsTheOldestThatFitAndFailsTheRest) {
  with_budget(200);
  const std::string older = submit(64, 64, 8).id;
  clock_.advance_ms(10);
  const std::string newer = submit(64, 64, 8).id;
  with_budget(100);  // lowered: only one of them fits
  EXPECT_EQ(s().job(older)->state, JobState::queued);
  EXPECT_EQ(s().job(older)->tiles_total, 64);
  const JobRecord failed = *s().job(newer);
  EXPECT_EQ(failed.state, JobState::failed);
  EXPECT_EQ(failed.tiles_total, 0);
  EXPECT_NE(failed.error.find("not loaded at start"), std::string::npos) << failed.error;
  EXPECT_EQ(scheduler_->job_memory(), 64 * kTileBytes);
  // The one left out is removed like any finished job, and the farm renders the other.
  EXPECT_EQ(s().remove(newer), RemoveOutcome::removed);
  finish(older, worker());
  with_budget(100);
  EXPECT_FALSE(s().job(newer));
  EXPECT_EQ(s().job(older)->state, JobState::completed);
}

}  // namespace
}  // namespace tessera
