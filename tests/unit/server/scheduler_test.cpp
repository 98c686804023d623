#include "server/farm/scheduler.hpp"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <future>
#include <memory>
#include <regex>
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "common/image/image_io.hpp"
#include "server/farm/tile_order.hpp"
#include "tests/unit/server/scheduler_fixture.hpp"

namespace tessera {
namespace {

using namespace test;

// Asks for a job's image the moment it is told the job completed, on the store thread, as
// a client following the farm's events may before the same write's other callbacks ran.
class AskOnCompletion : public FarmObserver {
 public:
  explicit AskOnCompletion(Scheduler& scheduler) : scheduler_(scheduler) {}
  void jobs_changed(const std::vector<JobRecord>& jobs) override {
    for (const JobRecord& job : jobs) {
      if (job.state != JobState::completed || asked_.exchange(true)) continue;
      scheduler_.assemble(job.id, [this](std::shared_ptr<const Image> image) {
        image_.set_value(std::move(image));
      });
    }
  }
  void tiles_changed(const std::vector<TileChange>&) override {}
  bool wants_tiles(const std::string&) override { return false; }
  void workers_changed(const std::vector<std::pair<WorkerRecord, WorkerChange>>&) override {}
  void job_removed(const std::string&) override {}
  // Null when no image came within a few seconds.
  std::shared_ptr<const Image> image() {
    auto future = image_.get_future();
    if (future.wait_for(std::chrono::seconds(10)) != std::future_status::ready) return nullptr;
    return future.get();
  }

 private:
  Scheduler& scheduler_;
  std::atomic<bool> asked_{false};
  std::promise<std::shared_ptr<const Image>> image_;
};

TEST_F(SchedulerTest, TheImageAskedForAsSoonAsTheJobCompletesHasItsLastTiles) {
  AskOnCompletion observer(*scheduler_);
  scheduler_->observe(&observer);
  const std::string job = submit(64, 32, 16).id;  // 8 tiles
  const std::string w = worker();
  // The first tiles make the job's canvas; the last ones are pasted into it by a callback
  // of their write, which runs after the observer hears of the completion.
  const auto first = s().claim(w, 4);
  ASSERT_TRUE(first);
  ASSERT_EQ(deliver(*first, 0.25f), ResultOutcome::accepted);
  s().wait_for_images();
  finish(job, w, 0.25f);
  const std::shared_ptr<const Image> image = observer.image();
  scheduler_->observe(nullptr);
  ASSERT_TRUE(image);
  Image expected(64, 32);
  for (const TileRect& rect : split_into_tiles(64, 32, 16))
    expected.paste(rect, tile_pixels(rect, 0.25f));
  EXPECT_TRUE(same_bits(image->pixels(), expected.pixels()));
}

TEST_F(SchedulerTest, SubmitClaimCompleteAssemblesTheImageBitExactly) {
  const JobRecord submitted = submit(100, 37, 32);
  EXPECT_TRUE(std::regex_match(submitted.id, std::regex("j-[0-9a-f]{32}")));
  EXPECT_EQ(submitted.state, JobState::queued);
  EXPECT_EQ(submitted.tiles_total, 8);
  EXPECT_EQ(submitted.created_at_ms, clock_.now_ms());

  const std::string w = worker();
  EXPECT_TRUE(std::regex_match(w, std::regex("w-[0-9a-f]{12}")));
  clock_.advance_ms(5);
  auto lease = s().claim(w);
  ASSERT_TRUE(lease);
  EXPECT_TRUE(std::regex_match(lease->id, std::regex("l-[0-9a-f]{16}")));
  EXPECT_EQ(lease->expires_at_ms, clock_.now_ms() + timeout_ms);
  EXPECT_EQ(lease->scene_digest, submitted.scene_digest);
  EXPECT_EQ(s().job(submitted.id)->state, JobState::running);
  EXPECT_EQ(s().job(submitted.id)->started_at_ms, clock_.now_ms());
  EXPECT_EQ(s().job(submitted.id)->tiles_rendering, 1);
  EXPECT_EQ(info_of(w).state, WorkerState::rendering);
  EXPECT_EQ(info_of(w).current_job, submitted.id);
  EXPECT_EQ(info_of(w).current_tile, lease->tiles[0].index);
  ASSERT_EQ(deliver(*lease), ResultOutcome::accepted);
  EXPECT_EQ(info_of(w).state, WorkerState::idle);
  finish(submitted.id, w);

  const JobRecord done = *s().job(submitted.id);
  EXPECT_EQ(done.state, JobState::completed);
  EXPECT_EQ(done.tiles_done, 8);
  EXPECT_EQ(done.tiles_rendering, 0);
  EXPECT_EQ(done.rays, 80u);
  EXPECT_EQ(done.finished_at_ms, clock_.now_ms());
  EXPECT_EQ(info_of(w).tiles_rendered, 8u);

  Image expected(100, 37);
  for (const TileRect& rect : split_into_tiles(100, 37, 32))
    expected.paste(rect, tile_pixels(rect, 0.0f));
  EXPECT_TRUE(same_bits(s().assemble(submitted.id)->pixels(), expected.pixels()));
  s().wait_for_images();
  const auto path = store_->data_dir() / "images" / (submitted.id + ".exr");
  ASSERT_TRUE(std::filesystem::exists(path));
  EXPECT_TRUE(same_bits(read_image(path).pixels(), expected.pixels()));
}

TEST_F(SchedulerTest, HigherPriorityFirstThenOldestThenId) {
  const std::string low = submit(8, 8, 8, 10).id;
  clock_.advance_ms(1);
  const std::string first_normal = submit(8, 8, 8, 50).id;
  clock_.advance_ms(1);
  const std::string a = submit(8, 8, 8, 50).id;  // same millisecond: the lower id goes first
  const std::string b = submit(8, 8, 8, 50).id;
  clock_.advance_ms(1);
  const std::string urgent = submit(8, 8, 8, 90).id;

  std::vector<std::string> claimed;
  for (int i = 0; i < 5; ++i) claimed.push_back(s().claim(worker())->job_id);
  EXPECT_EQ(claimed,
            (std::vector<std::string>{urgent, first_normal, std::min(a, b), std::max(a, b), low}));
  EXPECT_FALSE(s().claim(worker()));
}

TEST_F(SchedulerTest, TilesGoOutCentreFirst) {
  submit(96, 96, 32);  // 3x3 tiles
  const std::string w = worker();
  std::vector<int> order;
  while (auto lease = s().claim(w)) {
    order.push_back(lease->tiles[0].index);
    ASSERT_EQ(deliver(*lease), ResultOutcome::accepted);
  }
  EXPECT_EQ(order, (std::vector<int>{4, 1, 3, 5, 7, 0, 2, 6, 8}));

  // Wide image: the middle column pair ties; ties go by index.
  const auto tiles = split_into_tiles(4, 1, 1);
  EXPECT_EQ(centre_first_order(tiles, 4, 1), (std::vector<int>{1, 2, 0, 3}));
}

TEST_F(SchedulerTest, ReconnectingWorkerGetsItsLeaseBack) {
  submit(64, 64, 32);
  const std::string w = worker();
  const LeaseRecord first = *s().claim(w);
  clock_.advance_ms(1000);
  const LeaseRecord again = *s().claim(w);
  EXPECT_EQ(again.id, first.id);
  EXPECT_EQ(again.tiles[0].index, first.tiles[0].index);
  EXPECT_EQ(again.expires_at_ms, first.expires_at_ms);
  EXPECT_EQ(s().job(first.job_id)->tiles_rendering, 1);
}

TEST_F(SchedulerTest, HeartbeatExtendsAndTheLeaseExpiresExactlyAfterTheTimeout) {
  const std::string job = submit(16, 16, 16).id;  // one tile
  const std::string w1 = worker("one");
  const std::string w2 = worker("two");
  const LeaseRecord lease = *s().claim(w1);

  clock_.advance_ms(20'000);
  const auto extended = s().heartbeat(lease.id);
  ASSERT_TRUE(extended);
  EXPECT_EQ(extended->id, lease.id);
  EXPECT_EQ(extended->expires_at_ms, clock_.now_ms() + timeout_ms);

  clock_.advance_ms(timeout_ms - 1);
  s().expire_leases();
  EXPECT_FALSE(s().claim(w2));  // still w1's
  EXPECT_EQ(s().job(job)->tiles_rendering, 1);

  clock_.advance_ms(1);
  s().expire_leases();
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);
  EXPECT_EQ(info_of(w1).state, WorkerState::idle);
  EXPECT_FALSE(s().heartbeat(lease.id));

  const auto second = s().claim(w2);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->tiles[0].index, lease.tiles[0].index);
  EXPECT_NE(second->id, lease.id);
  EXPECT_EQ(second->worker_id, w2);
}

TEST_F(SchedulerTest, ClaimReapsExpiredLeasesAndALateHeartbeatIsLost) {
  submit(16, 16, 16);
  const LeaseRecord lease = *s().claim(worker());
  clock_.advance_ms(timeout_ms);
  EXPECT_FALSE(s().heartbeat(lease.id));
  const std::string other = worker();
  const auto second = s().claim(other);
  ASSERT_TRUE(second);
  EXPECT_NE(second->id, lease.id);
}

TEST_F(SchedulerTest, StaleResultIsRefusedAfterReassignment) {
  const std::string job = submit(16, 16, 16).id;
  const LeaseRecord old_lease = *s().claim(worker());
  clock_.advance_ms(timeout_ms);
  s().expire_leases();
  const LeaseRecord new_lease = *s().claim(worker());

  EXPECT_EQ(deliver(old_lease, 1.0f), ResultOutcome::stale);
  EXPECT_EQ(s().job(job)->tiles_done, 0);
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), Image(16, 16).pixels()));

  EXPECT_EQ(deliver(new_lease, 2.0f), ResultOutcome::accepted);
  EXPECT_EQ(deliver(old_lease, 1.0f), ResultOutcome::stale);
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), tile_pixels(new_lease.tiles[0].rect, 2.0f)));
  s().wait_for_images();
  EXPECT_TRUE(same_bits(read_image(ImageFiles(store_->data_dir()).path(job)).pixels(),
                        tile_pixels(new_lease.tiles[0].rect, 2.0f)));
}

TEST_F(SchedulerTest, ExpiredLeaseNotYetReassignedIsStillAccepted) {
  const std::string job = submit(16, 16, 16).id;
  const LeaseRecord lease = *s().claim(worker());
  clock_.advance_ms(timeout_ms + 5000);  // nobody reaped it
  EXPECT_EQ(deliver(lease), ResultOutcome::accepted);
  EXPECT_EQ(s().job(job)->state, JobState::completed);
}

TEST_F(SchedulerTest, DuplicateResultChangesNothing) {
  const std::string job = submit(32, 16, 16).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w);
  ASSERT_EQ(deliver(lease, 1.0f, 7), ResultOutcome::accepted);
  EXPECT_EQ(deliver(lease, 9.0f, 7), ResultOutcome::duplicate);
  EXPECT_EQ(s().job(job)->rays, 7u);
  EXPECT_EQ(s().job(job)->tiles_done, 1);
  EXPECT_EQ(info_of(w).tiles_rendered, 1u);
  Image expected(32, 16);
  expected.paste(lease.tiles[0].rect, tile_pixels(lease.tiles[0].rect, 1.0f));
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), expected.pixels()));
  reopen();  // duplicates are recognised from the store too
  EXPECT_EQ(deliver(lease, 9.0f, 7), ResultOutcome::duplicate);
}

TEST_F(SchedulerTest, WrongSizeIsRefusedAndTheLeaseKept) {
  const std::string job = submit(16, 16, 16).id;
  const LeaseRecord lease = *s().claim(worker());
  std::vector<float> short_pixels = tile_pixels(lease.tiles[0].rect, 0.0f);
  short_pixels.pop_back();
  EXPECT_EQ(s().complete(lease.id, short_pixels, 1), ResultOutcome::wrong_size);
  EXPECT_EQ(s().job(job)->tiles_done, 0);
  EXPECT_TRUE(s().heartbeat(lease.id));
  EXPECT_EQ(deliver(lease), ResultOutcome::accepted);
}

TEST_F(SchedulerTest, CancelWithdrawsLeases) {
  const std::string job = submit(64, 64, 32).id;
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w);
  clock_.advance_ms(10);
  EXPECT_EQ(s().cancel(job), CancelOutcome::canceled);
  const JobRecord canceled = *s().job(job);
  EXPECT_EQ(canceled.state, JobState::canceled);
  EXPECT_EQ(canceled.finished_at_ms, clock_.now_ms());
  EXPECT_EQ(canceled.tiles_rendering, 0);
  EXPECT_FALSE(s().heartbeat(lease.id));
  EXPECT_EQ(deliver(lease), ResultOutcome::stale);
  EXPECT_EQ(info_of(w).state, WorkerState::idle);
  EXPECT_FALSE(s().claim(w));
  EXPECT_EQ(s().cancel(job), CancelOutcome::already_finished);
  EXPECT_EQ(s().cancel("j-000000000000"), CancelOutcome::not_found);
}

TEST_F(SchedulerTest, RemoveOnlyFinishedJobs) {
  const JobRecord running = submit(16, 16, 16, 50, R"({"a":1})");
  clock_.advance_ms(1);
  const JobRecord sharing = submit(16, 16, 16, 50, R"({"a":1})");
  const JobRecord own = submit(16, 16, 16, 40, R"({"b":2})");
  EXPECT_EQ(running.scene_digest, sharing.scene_digest);
  EXPECT_EQ(s().remove(running.id), RemoveOutcome::not_finished);
  EXPECT_EQ(s().remove("j-000000000000"), RemoveOutcome::not_found);

  const std::string w = worker();
  finish(running.id, w);
  s().wait_for_images();
  ASSERT_TRUE(std::filesystem::exists(ImageFiles(store_->data_dir()).path(running.id)));
  EXPECT_EQ(s().remove(running.id), RemoveOutcome::removed);
  EXPECT_FALSE(s().job(running.id));
  EXPECT_FALSE(std::filesystem::exists(ImageFiles(store_->data_dir()).path(running.id)));
  EXPECT_TRUE(s().scene_json(sharing.scene_digest));  // still used by `sharing`

  ASSERT_EQ(s().cancel(own.id), CancelOutcome::canceled);
  EXPECT_EQ(s().remove(own.id), RemoveOutcome::removed);
  EXPECT_FALSE(s().scene_json(own.scene_digest));
  reopen();
  EXPECT_FALSE(s().job(running.id));
  EXPECT_FALSE(s().job(own.id));
  EXPECT_TRUE(s().job(sharing.id));
}

TEST_F(SchedulerTest, RestartKeepsDoneTilesLeasesAndFinishedStates) {
  const std::string job = submit(96, 96, 32).id;  // 9 tiles
  const std::string canceled = submit(32, 32, 32, 10).id;
  ASSERT_EQ(s().cancel(canceled), CancelOutcome::canceled);
  const std::string w1 = worker("one");
  const std::string w2 = worker("two");
  std::set<int> done;
  for (int i = 0; i < 4; ++i) {
    const LeaseRecord lease = *s().claim(w1);
    ASSERT_EQ(deliver(lease), ResultOutcome::accepted);
    done.insert(lease.tiles[0].index);
  }
  const LeaseRecord held = *s().claim(w2);

  reopen();
  const JobRecord after = *s().job(job);
  EXPECT_EQ(after.state, JobState::running);
  EXPECT_EQ(after.tiles_done, 4);
  EXPECT_EQ(after.rays, 40u);
  EXPECT_EQ(s().job(canceled)->state, JobState::canceled);
  EXPECT_EQ(info_of(w1).state, WorkerState::gone);  // until it talks to us again
  EXPECT_EQ(info_of(w2).state, WorkerState::rendering);
  EXPECT_EQ(info_of(w1).tiles_rendered, 4u);

  const LeaseRecord back = *s().claim(w2);
  EXPECT_EQ(back.id, held.id);
  EXPECT_EQ(back.tiles[0].index, held.tiles[0].index);
  while (auto lease = s().claim(w1)) {
    EXPECT_FALSE(done.contains(lease->tiles[0].index));
    EXPECT_NE(lease->tiles[0].index, held.tiles[0].index);
    ASSERT_EQ(deliver(*lease), ResultOutcome::accepted);
  }
  EXPECT_EQ(info_of(w1).state, WorkerState::idle);
  EXPECT_EQ(s().job(job)->state, JobState::running);
  ASSERT_EQ(deliver(back), ResultOutcome::accepted);
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  EXPECT_EQ(s().job(job)->rays, 90u);

  Image expected(96, 96);
  for (const TileRect& rect : split_into_tiles(96, 96, 32))
    expected.paste(rect, tile_pixels(rect, 0.0f));
  s().wait_for_images();
  EXPECT_TRUE(
      same_bits(read_image(ImageFiles(store_->data_dir()).path(job)).pixels(), expected.pixels()));
  reopen();
  EXPECT_EQ(s().job(job)->state, JobState::completed);
  EXPECT_EQ(s().job(canceled)->state, JobState::canceled);
  EXPECT_FALSE(s().claim(w1));
}

TEST_F(SchedulerTest, RestartGivesLeasesAFreshTimeout) {
  submit(16, 16, 16);
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w);
  scheduler_.reset();
  clock_.advance_ms(timeout_ms * 3);  // the coordinator was down for a while
  reopen();
  const auto back = s().heartbeat(lease.id);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->expires_at_ms, clock_.now_ms() + timeout_ms);
}

TEST_F(SchedulerTest, ReconcileCompletesARunningJobWhoseTilesAreAllDone) {
  const JobRecord job = submit(64, 32, 32);
  const std::string w = worker();
  finish(job.id, w, 3.0f);
  // As if the process had died after storing the last tile but before the job's update
  // and the image write.
  JobRow row = row_of(*s().job(job.id), "running");
  row.started_at_ms = job.created_at_ms;
  s().wait_for_images();
  clock_.advance_ms(100);
  reopen([&](Store& store) {
    store.update_job(row);
    std::filesystem::remove(ImageFiles(store.data_dir()).path(job.id));
  });
  const JobRecord after = *s().job(job.id);
  EXPECT_EQ(after.state, JobState::completed);
  EXPECT_EQ(after.finished_at_ms, clock_.now_ms());
  s().wait_for_images();
  ASSERT_TRUE(std::filesystem::exists(ImageFiles(store_->data_dir()).path(job.id)));
  EXPECT_TRUE(same_bits(read_image(ImageFiles(store_->data_dir()).path(job.id)).pixels(),
                        s().assemble(job.id)->pixels()));
}

TEST_F(SchedulerTest, ReconcileStartsAQueuedJobWithDoneTiles) {
  const JobRecord job = submit(64, 32, 32);
  ASSERT_EQ(deliver(*s().claim(worker())), ResultOutcome::accepted);
  const JobRow queued = row_of(*s().job(job.id), "queued");
  reopen([&](Store& store) { store.update_job(queued); });
  EXPECT_EQ(s().job(job.id)->state, JobState::running);
  EXPECT_NE(s().job(job.id)->started_at_ms, 0);
  EXPECT_TRUE(s().claim(worker()));
}

TEST_F(SchedulerTest, WorkerLeftAndReleaseGiveTheTileBack) {
  const std::string job = submit(16, 16, 16).id;
  const std::string w1 = worker("one");
  const std::string w2 = worker("two");
  const LeaseRecord first = *s().claim(w1);
  s().worker_left(w1);
  EXPECT_EQ(info_of(w1).state, WorkerState::left);
  EXPECT_EQ(info_of(w1).current_job, "");
  EXPECT_FALSE(s().heartbeat(first.id));
  EXPECT_EQ(deliver(first), ResultOutcome::stale);
  // It said goodbye: it registers again before it claims, and touching it revives nothing.
  EXPECT_FALSE(s().worker_known(w1));
  s().touch_worker(w1);
  EXPECT_EQ(info_of(w1).state, WorkerState::left);
  EXPECT_FALSE(s().claim(w1));

  const LeaseRecord second = *s().claim(w2);
  EXPECT_EQ(second.tiles[0].index, first.tiles[0].index);
  EXPECT_NE(second.id, first.id);
  s().release(second.id);
  EXPECT_EQ(info_of(w2).state, WorkerState::idle);
  EXPECT_EQ(s().job(job)->tiles_rendering, 0);

  // It comes back: not under its old id, which stays left, but registered anew.
  s().touch_worker(w1);
  EXPECT_EQ(info_of(w1).state, WorkerState::left);
  EXPECT_FALSE(s().worker_known("w-000000000000"));
  const std::string back = worker("one");
  EXPECT_NE(back, w1);
  EXPECT_TRUE(s().claim(back));
}

TEST_F(SchedulerTest, JobsAreListedNewestFirstWithFilterAndLimit) {
  const std::string a = submit(16, 16, 16).id;
  clock_.advance_ms(1);
  const std::string b = submit(16, 16, 16).id;
  const std::string c = submit(16, 16, 16).id;  // same ms as b: higher id first
  clock_.advance_ms(1);
  const std::string d = submit(16, 16, 16).id;
  ASSERT_EQ(s().cancel(b), CancelOutcome::canceled);

  std::vector<std::string> ids;
  for (const JobRecord& job : s().jobs(std::nullopt, 100)) ids.push_back(job.id);
  EXPECT_EQ(ids, (std::vector<std::string>{d, std::max(b, c), std::min(b, c), a}));
  EXPECT_EQ(s().jobs(std::nullopt, 2).size(), 2u);
  EXPECT_EQ(s().jobs(std::nullopt, 0).size(), 0u);
  const auto canceled = s().jobs(JobState::canceled, 100);
  ASSERT_EQ(canceled.size(), 1u);
  EXPECT_EQ(canceled[0].id, b);
  EXPECT_EQ(s().jobs(JobState::queued, 100).size(), 3u);
}

TEST_F(SchedulerTest, SceneIsFoundByItsSha256Digest) {
  const JobRecord job = submit(16, 16, 16, 50, "abc");
  EXPECT_EQ(job.scene_digest, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(s().scene_json(job.scene_digest), "abc");
  EXPECT_FALSE(s().scene_json("00"));
}

TEST_F(SchedulerTest, WorkAvailableCallbacksRunOutsideTheLock) {
  int calls = 0;
  // Calling back into the scheduler would deadlock were the lock still held.
  s().on_work_available([&] {
    ++calls;
    s().jobs(std::nullopt, 1);
  });
  submit(16, 16, 16);
  EXPECT_EQ(calls, 1);
  const std::string w = worker();
  const LeaseRecord lease = *s().claim(w);
  clock_.advance_ms(timeout_ms);
  s().expire_leases();
  EXPECT_EQ(calls, 2);
  s().expire_leases();  // nothing expired
  EXPECT_EQ(calls, 2);
  s().release((*s().claim(w)).id);
  EXPECT_EQ(calls, 3);
  EXPECT_FALSE(s().heartbeat(lease.id));
}

TEST_F(SchedulerTest, ConcurrentWorkersRenderEachTileOnce) {
  const std::string job = submit(160, 96, 16).id;  // 60 tiles
  std::vector<std::thread> threads;
  std::atomic<int> accepted = 0;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, id = worker()] {
      while (s().job(job)->state != JobState::completed) {
        s().touch_worker(id);
        if (const auto lease = s().claim(id)) {
          s().heartbeat(lease->id);
          if (deliver(*lease) == ResultOutcome::accepted) ++accepted;
        }
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(accepted.load(), 60);
  EXPECT_EQ(s().job(job)->rays, 600u);
  Image expected(160, 96);
  for (const TileRect& rect : split_into_tiles(160, 96, 16))
    expected.paste(rect, tile_pixels(rect, 0.0f));
  EXPECT_TRUE(same_bits(s().assemble(job)->pixels(), expected.pixels()));
}

TEST_F(SchedulerTest, UnknownLeasesAndWorkers) {
  EXPECT_FALSE(s().claim("w-000000000000"));
  EXPECT_FALSE(s().heartbeat("l-0000000000000000"));
  EXPECT_EQ(s().complete("l-0000000000000000", {}, 0), ResultOutcome::stale);
  s().release("l-0000000000000000");
  s().touch_worker("w-000000000000");
  s().worker_left("w-000000000000");
  EXPECT_FALSE(s().assemble("j-000000000000"));
  EXPECT_TRUE(s().workers().empty());
}

}  // namespace
}  // namespace tessera

namespace tessera {
namespace {

TEST_F(SchedulerTest, WorkersGoneOrLeftForAnHourLeaveTheListAndTheStore) {
  const auto listed = [&](const std::string& id) {
    for (const WorkerRecord& info : s().workers())
      if (info.id == id) return true;
    return false;
  };
  const std::string leaver = worker("leaver");
  const std::string stayer = worker("stayer");
  const std::int64_t hour = SchedulerConfig{}.forget_workers_after_ms;
  s().worker_left(leaver);
  clock_.advance_ms(hour - 1000);
  s().expire_leases();
  EXPECT_TRUE(listed(leaver)) << "forgotten before its hour";
  clock_.advance_ms(2000);
  s().touch_worker(stayer);  // one that talks stays, however long it has been around
  s().expire_leases();
  EXPECT_FALSE(listed(leaver));
  EXPECT_TRUE(listed(stayer));

  // Forgotten in the store too; and one silent since a restart goes after its hour.
  reopen();
  EXPECT_FALSE(listed(leaver));
  ASSERT_TRUE(listed(stayer));
  EXPECT_EQ(info_of(stayer).state, WorkerState::gone);
  clock_.advance_ms(hour + 1000);
  s().expire_leases();
  EXPECT_FALSE(listed(stayer));
  reopen();
  EXPECT_TRUE(s().workers().empty());
}

// A worker's secret (kept as its digest) names it across a restart, until it leaves; a
// lease names its holder while it is live.
TEST_F(SchedulerTest, ASecretNamesItsWorkerAcrossARestartUntilItLeaves) {
  const std::string a = s().register_worker("a", "host", 1, "digest-a").id;
  const std::string b = s().register_worker("b", "host", 1, "digest-b").id;
  EXPECT_EQ(s().worker_with_secret("digest-a"), a);
  EXPECT_EQ(s().worker_with_secret("digest-b"), b);
  EXPECT_EQ(s().worker_with_secret("digest-c"), std::nullopt);
  submit(32, 32, 16);
  const auto lease = s().claim(a);
  ASSERT_TRUE(lease);
  EXPECT_EQ(s().lease_holder(lease->id), a);
  EXPECT_EQ(s().lease_holder("l-none"), std::nullopt);

  reopen();
  EXPECT_EQ(s().worker_with_secret("digest-a"), a) << "the secret did not outlive a restart";
  EXPECT_EQ(s().lease_holder(lease->id), a);
  s().worker_left(a);
  EXPECT_EQ(s().worker_with_secret("digest-a"), std::nullopt) << "a worker that left proves";
  EXPECT_EQ(s().lease_holder(lease->id), std::nullopt) << "its lease ended with it";
  EXPECT_EQ(s().worker_with_secret("digest-b"), b);
}

}  // namespace
}  // namespace tessera
