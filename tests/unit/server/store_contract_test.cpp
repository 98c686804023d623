// What the Scheduler counts on of any Store, checked on each: the SQLite store a coordinator
// runs on and the memory store its unit tests run on must not drift apart, or those tests
// would prove a scheduler that the farm does not run.
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/farm/memory_store.hpp"
#include "server/farm/sqlite_store.hpp"
#include "tests/unit/server/test_dir.hpp"

namespace tessera {
namespace {

using MakeStore = std::function<std::unique_ptr<Store>(const std::filesystem::path&)>;

struct StoreKind {
  std::string name;
  MakeStore make;
};

JobRow job_row(const std::string& id, const std::string& digest) {
  JobRow job;
  job.id = id;
  job.name = "name of " + id;
  job.state = "queued";
  job.width = 40;
  job.height = 20;
  job.tile_size = 20;
  job.scene_digest = digest;
  return job;
}

class StoreContractTest : public ::testing::TestWithParam<StoreKind> {
 protected:
  void SetUp() override {
    dir_ = test::fresh_test_dir("tessera-store-contract");
    store_ = GetParam().make(dir_);
  }
  void TearDown() override {
    store_.reset();
    std::filesystem::remove_all(dir_);
  }
  // The pixels of the job's tiles as the store hands them back, 2 floats a tile.
  std::vector<std::pair<int, std::vector<float>>> pixels_of(
      const std::string& job_id, const std::function<bool(int)>& wanted = {}) {
    std::vector<std::pair<int, std::vector<float>>> seen;
    store_->for_each_tile_pixels(
        job_id, [](int) { return std::size_t{2}; },
        [&](int index, std::span<const float> pixels) {
          seen.emplace_back(index, std::vector<float>(pixels.begin(), pixels.end()));
        },
        wanted);
    return seen;
  }

  std::filesystem::path dir_;
  std::unique_ptr<Store> store_;
};

TEST_P(StoreContractTest, AChangeThatThrowsStoresNothingOfIt) {
  store_->insert_job(job_row("j-0", "d0"), "{}");
  const std::vector<float> pixels{1, 2};
  const std::vector<std::span<const float>> tiles{pixels};
  EXPECT_THROW(store_->atomically([&] {
    store_->insert_job(job_row("j-1", "d1"), "{}");
    store_->put_lease({"l-1", "j-1", "w-1", {0, 1}});
    store_->insert_result({0, "j-1", "l-1", "w-1", {0}, {5}, 0}, tiles);
    store_->update_job(job_row("j-0", "d0"));
    store_->upsert_worker({"w-1", "box", "host", 4, "idle", 0, 0, ""});
    store_->delete_job("j-0");
    throw std::runtime_error("the disk is full");
  }),
               std::runtime_error);
  const StoredState state = store_->load();
  ASSERT_EQ(state.jobs.size(), 1u);
  EXPECT_EQ(state.jobs[0].id, "j-0");
  EXPECT_TRUE(state.leases.empty());
  EXPECT_TRUE(state.results.empty());
  EXPECT_TRUE(state.workers.empty());
  EXPECT_FALSE(store_->scene_json("d1"));
  EXPECT_EQ(store_->scene_json("d0"), "{}");
}

TEST_P(StoreContractTest, ALeaseIsReplacedWholeAndKeepsItsJob) {
  store_->insert_job(job_row("j-1", "d1"), "{}");
  store_->put_lease({"l-1", "j-1", "w-1", {3, 4, 5}});
  store_->put_lease({"l-1", "j-1", "w-2", {5}});
  StoredState state = store_->load();
  ASSERT_EQ(state.leases.size(), 1u);
  EXPECT_EQ(state.leases[0].worker_id, "w-2");
  EXPECT_EQ(state.leases[0].tiles, (std::vector<int>{5}));
  store_->delete_lease("l-1");
  EXPECT_TRUE(store_->load().leases.empty());
}

TEST_P(StoreContractTest, ResultsComeBackInTheOrderStoredWithTheirPixels) {
  store_->insert_job(job_row("j-1", "d1"), "{}");
  store_->insert_job(job_row("j-2", "d2"), "{}");
  const std::vector<float> a{1, 2, 3, 4}, b{5, 6}, other{9, 9};
  const std::int64_t first = store_->insert_result(
      {0, "j-1", "l-1", "w-1", {7, 2}, {10, 20}, 0},
      std::vector<std::span<const float>>{std::span(a).first(2), std::span(a).last(2)});
  store_->insert_result({0, "j-2", "l-2", "w-1", {0}, {1}, 0},
                        std::vector<std::span<const float>>{other});
  const std::int64_t second = store_->insert_result({0, "j-1", "l-3", "w-2", {0}, {30}, 0},
                                                    std::vector<std::span<const float>>{b});
  EXPECT_LT(first, second);
  const StoredState state = store_->load();
  ASSERT_EQ(state.results.size(), 3u);
  EXPECT_EQ(state.results[0].tiles, (std::vector<int>{7, 2}));
  EXPECT_EQ(state.results[0].rays, (std::vector<std::uint64_t>{10, 20}));
  EXPECT_EQ(state.results[0].pixel_bytes, 16);
  EXPECT_EQ(state.results[2].worker_id, "w-2");
  using Seen = std::vector<std::pair<int, std::vector<float>>>;
  EXPECT_EQ(pixels_of("j-1"), (Seen{{7, {1, 2}}, {2, {3, 4}}, {0, {5, 6}}}));
  EXPECT_EQ(pixels_of("j-1", [](int index) { return index == 2; }), (Seen{{2, {3, 4}}}));
  store_->delete_result(first);
  EXPECT_EQ(pixels_of("j-1"), (Seen{{0, {5, 6}}}));
}

TEST_P(StoreContractTest, AnUpdateChangesWhatAJobMayChangeOnly) {
  store_->insert_job(job_row("j-1", "d1"), "{}");
  JobRow next = job_row("j-1", "d1");
  next.state = "failed";
  next.error = "why";
  next.priority = 90;
  next.rays = 77;
  next.width = 4000;  // fixed at submit
  store_->update_job(next);
  store_->update_job(job_row("j-9", "d9"));  // no such job: nothing happens
  const StoredState state = store_->load();
  ASSERT_EQ(state.jobs.size(), 1u);
  EXPECT_EQ(state.jobs[0].state, "failed");
  EXPECT_EQ(state.jobs[0].error, "why");
  EXPECT_EQ(state.jobs[0].priority, 90);
  EXPECT_EQ(state.jobs[0].rays, 77u);
  EXPECT_EQ(state.jobs[0].width, 40);
}

TEST_P(StoreContractTest, RemovingAJobTakesItsRowsAndASceneNoOtherJobUses) {
  store_->insert_job(job_row("j-1", "shared"), "{\"a\":1}");
  store_->insert_job(job_row("j-2", "shared"), "{\"a\":1}");
  store_->insert_job(job_row("j-3", "own"), "{}");
  const std::vector<float> pixels{1, 2};
  for (const char* job : {"j-1", "j-2", "j-3"}) {
    store_->put_lease({std::string("l-") + job, job, "w", {1}});
    store_->insert_result({0, job, "l", "w", {0}, {1}, 0},
                          std::vector<std::span<const float>>{pixels});
    store_->put_tile_failure({job, 1, 2, "boom"});
  }
  store_->delete_job("j-1");
  store_->delete_job("j-3");
  const StoredState state = store_->load();
  ASSERT_EQ(state.jobs.size(), 1u);
  for (const auto& lease : state.leases) EXPECT_EQ(lease.job_id, "j-2");
  for (const auto& result : state.results) EXPECT_EQ(result.job_id, "j-2");
  for (const auto& failure : state.failures) EXPECT_EQ(failure.job_id, "j-2");
  EXPECT_EQ(state.leases.size() + state.results.size() + state.failures.size(), 3u);
  EXPECT_EQ(store_->scene_json("shared"), "{\"a\":1}");
  EXPECT_FALSE(store_->scene_json("own"));
  EXPECT_TRUE(pixels_of("j-1").empty());
}

TEST_P(StoreContractTest, RowsOfAJobNotStoredAreRefused) {
  const std::vector<float> pixels{1, 2};
  EXPECT_THROW(store_->put_lease({"l-1", "nope", "w", {0}}), std::runtime_error);
  EXPECT_THROW(store_->insert_result({0, "nope", "l", "w", {0}, {1}, 0},
                                     std::vector<std::span<const float>>{pixels}),
               std::runtime_error);
  EXPECT_THROW(store_->put_tile_failure({"nope", 0, 1, "x"}), std::runtime_error);
  store_->insert_job(job_row("j-1", "d1"), "{}");
  EXPECT_THROW(store_->insert_job(job_row("j-1", "d1"), "{}"), std::runtime_error);
}

TEST_P(StoreContractTest, AFailureAndAWorkerAreReplacedWhole) {
  store_->insert_job(job_row("j-1", "d1"), "{}");
  store_->put_tile_failure({"j-1", 4, 1, "first"});
  store_->put_tile_failure({"j-1", 4, 2, "second"});
  store_->upsert_worker({"w-1", "box", "host", 4, "idle", 3, 100, "digest"});
  store_->upsert_worker({"w-1", "box", "host", 8, "rendering", 5, 200, "digest", true});
  store_->update_worker_seen("w-1", 300);
  store_->update_worker_seen("w-9", 300);  // no such worker: nothing happens
  StoredState state = store_->load();
  ASSERT_EQ(state.failures.size(), 1u);
  EXPECT_EQ(state.failures[0].attempts, 2);
  EXPECT_EQ(state.failures[0].last_error, "second");
  ASSERT_EQ(state.workers.size(), 1u);
  EXPECT_EQ(state.workers[0].threads, 8);
  EXPECT_EQ(state.workers[0].state, "rendering");
  EXPECT_EQ(state.workers[0].last_seen_ms, 300);
  EXPECT_TRUE(state.workers[0].draining);
  store_->delete_worker("w-1");
  EXPECT_TRUE(store_->load().workers.empty());
}

INSTANTIATE_TEST_SUITE_P(
    EachStore, StoreContractTest,
    ::testing::Values(StoreKind{"Sqlite",
                                [](const std::filesystem::path& dir) -> std::unique_ptr<Store> {
                                  return std::make_unique<SqliteStore>(dir);
                                }},
                      StoreKind{"Memory",
                                [](const std::filesystem::path& dir) -> std::unique_ptr<Store> {
                                  return std::make_unique<MemoryStore>(dir);
                                }}),
    [](const ::testing::TestParamInfo<StoreKind>& info) { return info.param.name; });

}  // namespace
}  // namespace tessera
