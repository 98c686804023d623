// The Scheduler answers at once, in memory, but its caller may give the answer only once
// when_stored() says so: by then, what the answer reports is in the database, as another
// connection (the next coordinator's) reads it.
#include <filesystem>
#include <future>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/farm/sqlite_db.hpp"
#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using test::SchedulerTest;
using test::SqliteSchedulerTest;

class SchedulerDurabilityTest : public SqliteSchedulerTest {
 protected:
  // Counts `table`'s rows from a connection of its own when `pending` may be answered.
  template <class T>
  std::string rows_when_stored(const Pending<T>& pending, const std::string& table) {
    std::promise<std::string> rows;
    scheduler_->when_stored(pending, [&](const std::string& error) {
      rows.set_value(error.empty() ? SqliteDb(store_->data_dir() / "tessera.db")
                                         .query_text("SELECT count(*) FROM " + table)
                                   : "refused: " + error);
    });
    return rows.get_future().get();
  }
};

TEST_F(SchedulerDurabilityTest, ALeaseAndAResultAreInTheDatabaseBeforeTheyAreAnswered) {
  const std::string job = submit(64, 32, 32).id;  // 2 tiles
  const std::string w = worker();
  for (int round = 1; round <= 2; ++round) {
    const Pending<std::optional<LeaseRecord>> claimed = scheduler_->claim(w, 1);
    ASSERT_TRUE(claimed.value);
    EXPECT_TRUE(claimed.wrote);
    EXPECT_EQ(rows_when_stored(claimed, "leases"), "1");
    const std::vector<float> pixels = test::tile_pixels(claimed.value->tiles[0].rect, 0.0f);
    const Pending<ResultOutcome> result = scheduler_->complete(claimed.value->id, pixels, 10);
    ASSERT_EQ(result.value, ResultOutcome::accepted);
    EXPECT_EQ(rows_when_stored(result, "results"), std::to_string(round));
  }
  EXPECT_EQ(s().job(job)->state, JobState::completed);
}

TEST_F(SchedulerDurabilityTest, AnAnswerThatChangedNothingWaitsForWhatItReports) {
  // A status read from memory may show a change still queued; Scheduler::durable() is
  // given once that change is stored.
  const std::string job = submit(32, 32, 32).id;
  const std::string w = worker();
  const Pending<std::optional<LeaseRecord>> claimed = scheduler_->claim(w, 1);
  ASSERT_TRUE(claimed.value);
  const Written now = scheduler_->durable();
  EXPECT_FALSE(now.wrote);
  EXPECT_GE(now.ticket, claimed.ticket);
  EXPECT_EQ(rows_when_stored(now, "leases"), "1");
  EXPECT_EQ(s().job(job)->tiles_rendering, 1);
}

TEST_F(SchedulerDurabilityTest, ALastResultTheStoreRefusesFailsTheJobBeforeAnyoneHears) {
  // /dev/full answers every write with ENOSPC: the job's pixel file is made one.
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  const std::string job = submit(32, 32, 32).id;  // 1 tile: its result completes the job
  const std::string w = worker();
  std::filesystem::create_directories(sqlite().pixel_path(job).parent_path());
  std::filesystem::create_symlink("/dev/full", sqlite().pixel_path(job));
  const Pending<std::optional<LeaseRecord>> claimed = scheduler_->claim(w, 1);
  ASSERT_TRUE(claimed.value);
  const std::uint64_t refusals = scheduler_->refusals();
  const std::vector<float> pixels = test::tile_pixels(claimed.value->tiles[0].rect, 0.0f);
  const Pending<ResultOutcome> result = scheduler_->complete(claimed.value->id, pixels, 10);
  EXPECT_EQ(result.value, ResultOutcome::accepted);  // in memory, at once...
  // ...and refused by the store: by the time the answer may go, the job has failed and the
  // refusal is counted, so that a status made before it is made again.
  std::promise<std::pair<std::string, std::uint64_t>> told;
  scheduler_->when_stored(result, [&](const std::string& error) {
    told.set_value({error, scheduler_->refusals()});
  });
  const auto [error, counted] = told.get_future().get();
  EXPECT_NE(error.find("the disk is full"), std::string::npos) << error;
  EXPECT_EQ(counted, refusals + 1);
  EXPECT_EQ(s().job(job)->state, JobState::failed);
  EXPECT_NE(s().job(job)->error.find("cannot store"), std::string::npos) << s().job(job)->error;
}

TEST_F(SchedulerDurabilityTest,
       TilesWhoseResultTheStoreRefusedArePendingAgainAndARetryRendersThem) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  const std::string job = submit(64, 32, 32).id;  // 2 tiles
  const std::string w = worker();
  std::filesystem::create_directories(sqlite().pixel_path(job).parent_path());
  std::filesystem::create_symlink("/dev/full", sqlite().pixel_path(job));
  const auto first = s().claim(w);
  ASSERT_TRUE(first);
  EXPECT_NE(deliver(*first), ResultOutcome::accepted);  // refused once stored
  // Memory says what the store has: the job failed, and no tile is done, so that a retry
  // renders them rather than completing the job without their pixels.
  EXPECT_EQ(s().job(job)->state, JobState::failed);
  EXPECT_EQ(s().job(job)->tiles_done, 0);
  EXPECT_EQ(s().job(job)->rays, 0u);

  std::filesystem::remove(sqlite().pixel_path(job));  // space back
  EXPECT_EQ(s().retry(job).result, ControlOutcome::Result::done);
  finish(job, w, 7.0f);
  reopen();
  const JobRecord after = *s().job(job);
  EXPECT_EQ(after.state, JobState::completed);
  EXPECT_EQ(after.tiles_done, 2);
  int tiles = 0;
  for (const ResultRow& row : store_->load().results) tiles += static_cast<int>(row.tiles.size());
  EXPECT_EQ(tiles, 2);
}

// The same refusal on the memory store, whatever the machine has of /dev/full: the job
// fails as the store left it, and renders the refused tiles again once retried.
TEST_F(SchedulerTest, AResultTheMemoryStoreRefusesFailsItsJobUntilRetried) {
  const std::string job = submit(64, 32, 32).id;  // 2 tiles
  const std::string w = worker();
  const auto first = s().claim(w);
  ASSERT_TRUE(first);
  memory().refuse_writes("store: the disk is full");
  EXPECT_EQ(deliver(*first), ResultOutcome::unstored);
  EXPECT_EQ(s().job(job)->state, JobState::failed);
  EXPECT_NE(s().job(job)->error.find("the disk is full"), std::string::npos) << s().job(job)->error;
  EXPECT_EQ(s().job(job)->tiles_done, 0);
  EXPECT_EQ(scheduler_->refusals(), 1u);

  memory().refuse_writes(std::nullopt);
  EXPECT_EQ(s().retry(job).result, ControlOutcome::Result::done);
  finish(job, w, 7.0f);
  reopen();
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  EXPECT_EQ(s().job(job)->tiles_done, 2);
  EXPECT_EQ(store_->load().results.size(), 2u);
}

}  // namespace
}  // namespace tessera
