// The farm's controls: priority, pause and resume, retry, draining and removing workers,
// and finding a job by a prefix of its id. Each must change what claims hand out, survive
// a restart, and refuse what makes no sense with a reason.
#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using namespace test;
using Result = ControlOutcome::Result;

TEST_F(SchedulerTest, ANewPriorityChangesWhichJobTheNextClaimTakes) {
  const std::string first = submit(8, 8, 8, 50).id;
  clock_.advance_ms(1);
  const std::string second = submit(8, 8, 8, 50).id;
  EXPECT_EQ(s().set_priority(second, 80).result, Result::done);
  EXPECT_EQ(s().job(second)->priority, 80);
  EXPECT_EQ(s().claim(worker())->job_id, second);
  EXPECT_EQ(s().claim(worker())->job_id, first);
  reopen();  // the priority was stored
  EXPECT_EQ(s().job(second)->priority, 80);
  EXPECT_EQ(s().set_priority("j-none", 10).result, Result::not_found);
}

TEST_F(SchedulerTest, AFinishedJobKeepsItsPriority) {
  const std::string job = submit(8, 8, 8).id;
  finish(job, worker());
  const ControlOutcome outcome = s().set_priority(job, 90);
  EXPECT_EQ(outcome.result, Result::refused);
  EXPECT_EQ(outcome.code, "already_finished");
  EXPECT_EQ(s().job(job)->priority, 50);
}

TEST_F(SchedulerTest, APausedJobsLeasesRunOutAndNoNewTileGoesOut) {
  const std::string job = submit(64, 32, 16).id;  // 8 tiles
  const std::string other = submit(16, 16, 16, 10).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 2);
  ASSERT_EQ(lease.tiles.size(), 2u);
  EXPECT_EQ(s().pause(job).result, Result::done);
  EXPECT_EQ(s().job(job)->state, JobState::paused);
  EXPECT_EQ(s().pause(job).result, Result::done) << "pausing twice does nothing";
  // The lease out keeps going: heartbeats renew it, but it gets no more tiles.
  ASSERT_TRUE(s().heartbeat(lease.id));
  const auto extended = s().extend(lease.id, 4);
  ASSERT_TRUE(extended);
  EXPECT_TRUE(extended->tiles.empty());
  // Its results are taken; other workers get the other job, then nothing.
  EXPECT_EQ(deliver(lease), ResultOutcome::accepted);
  EXPECT_EQ(s().job(job)->tiles_done, 2);
  EXPECT_EQ(s().job(job)->state, JobState::paused);
  const std::string w2 = worker("two");
  const LeaseRecord other_lease = *s().claim(w2);
  EXPECT_EQ(other_lease.job_id, other);
  EXPECT_EQ(deliver(other_lease), ResultOutcome::accepted);
  EXPECT_FALSE(s().claim(worker("three")));
  // A paused job never counts as stalled.
  clock_.advance_ms(config_.stall_timeout_ms + 1);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->state, JobState::paused);
  reopen();  // still paused after a restart
  EXPECT_EQ(s().job(job)->state, JobState::paused);
  EXPECT_FALSE(s().claim(w));
  EXPECT_EQ(s().resume(job).result, Result::done);
  EXPECT_EQ(s().job(job)->state, JobState::running) << "it had started";
  finish(job, w);
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  EXPECT_EQ(s().pause(job).code, "already_finished");
  EXPECT_EQ(s().resume(job).code, "already_finished");
}

TEST_F(SchedulerTest, AJobPausedBeforeItStartedResumesQueued) {
  const std::string job = submit(16, 16, 16).id;
  EXPECT_EQ(s().pause(job).result, Result::done);
  EXPECT_FALSE(s().claim(worker()));
  EXPECT_EQ(s().resume(job).result, Result::done);
  EXPECT_EQ(s().job(job)->state, JobState::queued);
  EXPECT_EQ(s().resume(job).result, Result::done) << "resuming a job not paused does nothing";
  EXPECT_EQ(s().claim(worker())->job_id, job);
}

TEST_F(SchedulerTest, ARetriedJobRendersOnlyTheTilesItLackedAndItsImageIsWhole) {
  config_.max_tile_attempts = 1;
  reopen();
  const std::string job = submit(64, 32, 16).id;  // 8 tiles
  const std::string w = worker();
  const LeaseRecord good = *s().claim(w, 3);
  ASSERT_EQ(deliver(good, 0.0f), ResultOutcome::accepted);
  const LeaseRecord bad = *s().claim(w, 1);
  s().fail_tile(bad.id, bad.tiles[0].index, "out of memory");
  ASSERT_EQ(s().job(job)->state, JobState::failed);
  EXPECT_EQ(s().retry("j-none").result, Result::not_found);
  // Not every job may be retried.
  const std::string running = submit(16, 16, 16).id;
  EXPECT_EQ(s().retry(running).code, "not_failed");

  EXPECT_EQ(s().retry(job).result, Result::done);
  const JobRecord retried = *s().job(job);
  EXPECT_EQ(retried.state, JobState::running);
  EXPECT_EQ(retried.error, "");
  EXPECT_EQ(retried.finished_at_ms, 0);
  EXPECT_EQ(retried.tiles_done, 3) << "the tiles done are kept";
  EXPECT_EQ(retried.health.tile_failures, 0);
  // The failed tile is no longer counted against the job: it goes out and is taken.
  int rendered = 0;
  while (s().job(job)->state == JobState::running) {
    const auto lease = s().claim(w);
    ASSERT_TRUE(lease);
    if (lease->job_id != job) {
      ASSERT_EQ(deliver(*lease), ResultOutcome::accepted);
      continue;
    }
    rendered += static_cast<int>(lease->tiles.size());
    ASSERT_EQ(deliver(*lease, 0.0f), ResultOutcome::accepted);
  }
  EXPECT_EQ(rendered, 5);
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  Image expected(64, 32);
  for (const TileRect& rect : split_into_tiles(64, 32, 16))
    expected.paste(rect, tile_pixels(rect, 0.0f));
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), expected.pixels()));
  s().wait_for_images();
  ASSERT_TRUE(s().image_file(job));
  EXPECT_TRUE(same_bits(read_image(*s().image_file(job)).pixels(), expected.pixels()));
  EXPECT_EQ(s().retry(job).code, "not_failed");
}

// Canceled by mistake: a retry brings the job back under its id, with its tiles done; the
// lease the cancel withdrew stays withdrawn, and the rest renders once.
TEST_F(SchedulerTest, ACanceledJobIsRetriedKeepingItsTilesDone) {
  const std::string job = submit(64, 32, 16).id;  // 8 tiles
  const std::string w = worker();
  ASSERT_EQ(deliver(*s().claim(w, 3), 0.5f), ResultOutcome::accepted);
  const LeaseRecord withdrawn = *s().claim(w, 2);
  ASSERT_EQ(s().cancel(job), CancelOutcome::canceled);
  ASSERT_EQ(s().job(job)->state, JobState::canceled);
  EXPECT_EQ(s().retry(job).result, Result::done);
  const JobRecord retried = *s().job(job);
  EXPECT_EQ(retried.state, JobState::running);
  EXPECT_EQ(retried.finished_at_ms, 0);
  EXPECT_EQ(retried.tiles_done, 3);
  EXPECT_EQ(deliver(withdrawn, 0.5f), ResultOutcome::stale);
  reopen();  // the retry is stored
  EXPECT_EQ(s().job(job)->state, JobState::running);
  int rendered = 0;
  while (const auto lease = s().claim(w, 100)) {
    rendered += static_cast<int>(lease->tiles.size());
    ASSERT_EQ(deliver(*lease, 0.5f), ResultOutcome::accepted);
  }
  EXPECT_EQ(rendered, 5);
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  Image expected(64, 32);
  for (const TileRect& rect : split_into_tiles(64, 32, 16))
    expected.paste(rect, tile_pixels(rect, 0.5f));
  s().wait_for_images();
  ASSERT_TRUE(s().image_file(job));
  EXPECT_TRUE(same_bits(read_image(*s().image_file(job)).pixels(), expected.pixels()));
}

TEST_F(SchedulerTest, ARetryAfterARestartForgetsTheStoredFailures) {
  config_.max_tile_attempts = 1;
  reopen();
  const std::string job = submit(16, 16, 16).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w);
  s().fail_tile(lease.id, 0, "bad");
  ASSERT_EQ(s().job(job)->state, JobState::failed);
  ASSERT_EQ(s().retry(job).result, Result::done);
  reopen();
  EXPECT_EQ(s().job(job)->state, JobState::running);
  EXPECT_EQ(s().job(job)->health.tile_failures, 0);
  finish(job, w);
}

TEST_F(SchedulerTest, ADrainingWorkerFinishesItsLeaseAndTakesNoMore) {
  const std::string job = submit(64, 32, 16).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 2);
  EXPECT_EQ(s().drain_worker(w, true).result, Result::done);
  EXPECT_TRUE(info_of(w).draining);
  // Its lease goes on, without more tiles; a reconnect gets the same lease back.
  EXPECT_TRUE(s().extend(lease.id, 4)->tiles.empty());
  EXPECT_EQ(s().claim(w)->id, lease.id);
  EXPECT_EQ(deliver(lease), ResultOutcome::accepted);
  EXPECT_FALSE(s().claim(w)) << "drained: no more tiles";
  EXPECT_EQ(s().claim(worker("other"))->job_id, job);
  reopen();  // still draining after a restart
  EXPECT_TRUE(info_of(w).draining);
  EXPECT_FALSE(s().claim(w));
  EXPECT_EQ(s().drain_worker(w, false).result, Result::done);
  EXPECT_FALSE(info_of(w).draining);
  EXPECT_EQ(s().claim(w)->job_id, job);
  EXPECT_EQ(s().drain_worker("w-none", true).result, Result::not_found);
}

TEST_F(SchedulerTest, ARemovedWorkersTilesGoBackAndItIsForgotten) {
  const std::string job = submit(64, 16, 16).id;  // 4 tiles: a batch of 2
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w, 2);
  ASSERT_EQ(lease.tiles.size(), 2u);
  EXPECT_EQ(s().remove_worker(w).result, Result::done);
  EXPECT_FALSE(s().worker_known(w));
  EXPECT_TRUE(s().workers().empty());
  EXPECT_FALSE(s().heartbeat(lease.id)) << "its lease is over";
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);
  EXPECT_EQ(s().claim(worker("other"), 2)->tiles.size(), 2u);
  reopen();
  for (const WorkerRecord& info : s().workers()) EXPECT_NE(info.id, w);
  EXPECT_EQ(s().remove_worker(w).result, Result::not_found);
}

TEST_F(SchedulerTest, JobsAreFoundByAPrefixOfTheirId) {
  std::vector<std::string> ids;
  for (int i = 0; i < 40; ++i) ids.push_back(submit(8, 8, 8).id);
  const std::string& one = ids[7];
  // Enough of an id names it alone (40 random ids share no 6 hex digits, or the
  // test would be wrong 1 time in about 400,000).
  EXPECT_EQ(s().job_ids_with_prefix(one.substr(0, 8), 10), std::vector<std::string>{one});
  EXPECT_EQ(s().job_ids_with_prefix(one, 10), std::vector<std::string>{one});
  EXPECT_EQ(s().job_ids_with_prefix("j-", 100).size(), 40u);
  EXPECT_EQ(s().job_ids_with_prefix("j-", 5).size(), 5u);
  EXPECT_TRUE(s().job_ids_with_prefix("j-x", 10).empty());
}

TEST_F(SchedulerTest, PagesOfTheJobListCoverEveryJobOnceNewestFirst) {
  std::vector<std::string> submitted;
  for (int i = 0; i < 25; ++i) {
    submitted.push_back(submit(8, 8, 8).id);
    clock_.advance_ms(1);
  }
  std::vector<std::string> paged;
  for (std::size_t offset = 0; offset < 30; offset += 10)
    for (const JobRecord& job : s().jobs(std::nullopt, 10, offset)) paged.push_back(job.id);
  EXPECT_EQ(paged, std::vector<std::string>(submitted.rbegin(), submitted.rend()));
  EXPECT_TRUE(s().jobs(std::nullopt, 10, 25).empty()) << "past the end";
  EXPECT_EQ(s().jobs(JobState::queued, 5, 20).size(), 5u);
}

}  // namespace
}  // namespace tessera
