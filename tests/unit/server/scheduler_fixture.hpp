// The Scheduler's unit-test fixtures: the state machine on a MemoryStore (SchedulerTest) or,
// for what the database holds, on a SqliteStore in the same temporary directory
// (SqliteSchedulerTest); a manual clock; and helpers that fill tiles with values that show
// any misplaced pixel.
#pragma once

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/server/test_dir.hpp"

#include "server/farm/memory_store.hpp"
#include "server/farm/scheduler.hpp"
#include "server/farm/sqlite_store.hpp"
#include "tests/unit/server/blocking_scheduler.hpp"

namespace tessera::test {

inline constexpr std::int64_t timeout_ms = 30'000;

inline Scene scene_of(int width, int height, int tile_size) {
  Scene scene;
  scene.width = width;
  scene.height = height;
  scene.render.tile_size = tile_size;
  return scene;
}

// Distinct, awkward values (negative, fractional, large) so that any misplaced or
// converted pixel shows up; `seed` tells uploads of the same tile apart.
inline float value_at(int x, int y, int channel, float seed) {
  return seed + static_cast<float>(x) * 1.25f - static_cast<float>(y) * 0.3f +
         static_cast<float>(channel) * 1e4f + 1.0f / 3.0f;
}

inline std::vector<float> tile_pixels(const TileRect& rect, float seed) {
  std::vector<float> pixels;
  for (int y = rect.y; y < rect.y + rect.height; ++y)
    for (int x = rect.x; x < rect.x + rect.width; ++x)
      for (int c = 0; c < 3; ++c) pixels.push_back(value_at(x, y, c, seed));
  return pixels;
}

// The job's row as the store has it, but in `state` (to stage a crash).
inline JobRow row_of(const JobRecord& job, const std::string& state) {
  JobRow row;
  row.id = job.id;
  row.name = job.name;
  row.priority = job.priority;
  row.state = state;
  row.width = job.width;
  row.height = job.height;
  row.tile_size = job.tile_size;
  row.scene_digest = job.scene_digest;
  row.created_at_ms = job.created_at_ms;
  row.rays = job.rays;
  return row;
}

inline bool same_bits(std::span<const float> a, std::span<const float> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

// The indexes of a lease's tiles, in its order.
inline std::vector<int> indexes_of(const LeaseRecord& lease) {
  std::vector<int> indexes;
  for (const LeaseTileRecord& tile : lease.tiles) indexes.push_back(tile.index);
  return indexes;
}

class SchedulerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::fresh_test_dir("tessera-scheduler-test");
    open();
  }
  void TearDown() override {
    scheduler_.reset();
    store_.reset();
    std::filesystem::remove_all(dir_);
  }

  // The store the scheduler keeps its state in; it outlives the scheduler.
  virtual std::unique_ptr<Store> make_store() { return std::make_unique<MemoryStore>(dir_); }
  // Whether a restart opens the store again, as from a file.
  virtual bool reopens_store() const { return false; }

  void open() {
    if (!store_) store_ = make_store();
    scheduler_ = std::make_unique<Scheduler>(*store_, clock_, config_);
  }
  // What a coordinator restart does: everything in memory is lost, what is stored stays.
  // `while_down` changes what the next start finds, as a crash at a bad moment would.
  void reopen(const std::function<void(Store&)>& while_down = {}) {
    scheduler_.reset();
    if (reopens_store()) store_.reset();
    if (while_down) {
      if (!store_) store_ = make_store();
      while_down(*store_);
    }
    open();
  }

  BlockingScheduler& s() { return blocking_; }
  // The memory store, to make it refuse writes (SchedulerTest only).
  MemoryStore& memory() { return dynamic_cast<MemoryStore&>(*store_); }
  std::string worker(const std::string& name = "w") {
    return s().register_worker(name, "host", 4).id;
  }
  JobRecord submit(int width, int height, int tile_size, int priority = 50,
                   const std::string& json = "{}") {
    return s().submit("job", priority, scene_of(width, height, tile_size), json);
  }
  ResultOutcome deliver(const LeaseRecord& lease, float seed = 0.0f, std::uint64_t rays = 10) {
    // Every tile the lease owes, in its order; the rays count once.
    std::vector<float> pixels;
    for (const LeaseTileRecord& tile : lease.tiles) {
      const std::vector<float> part = tile_pixels(tile.rect, seed);
      pixels.insert(pixels.end(), part.begin(), part.end());
    }
    return s().complete(lease.id, pixels, rays);
  }
  // Claims and completes tiles with one worker until the job is completed.
  void finish(const std::string& job_id, const std::string& worker_id, float seed = 0.0f) {
    while (s().job(job_id)->state != JobState::completed) {
      const auto lease = s().claim(worker_id);
      ASSERT_TRUE(lease);
      ASSERT_EQ(lease->job_id, job_id);
      ASSERT_EQ(deliver(*lease, seed), ResultOutcome::accepted);
    }
  }
  WorkerRecord info_of(const std::string& worker_id) {
    for (const WorkerRecord& w : s().workers())
      if (w.id == worker_id) return w;
    ADD_FAILURE() << "no worker " << worker_id;
    return {};
  }

  std::filesystem::path dir_;
  // Tests that need other settings change it and reopen().
  SchedulerConfig config_ = [] {
    SchedulerConfig config;
    config.lease_timeout_ms = timeout_ms;
    return config;
  }();
  ManualClock clock_;
  std::unique_ptr<Store> store_;
  std::unique_ptr<Scheduler> scheduler_;
  BlockingScheduler blocking_{scheduler_};
};

// For what the SQLite store writes, and what it finds after a crash: a restart opens the
// database again from its file.
class SqliteSchedulerTest : public SchedulerTest {
 protected:
  std::unique_ptr<Store> make_store() override { return std::make_unique<SqliteStore>(dir_); }
  bool reopens_store() const override { return true; }
  SqliteStore& sqlite() { return static_cast<SqliteStore&>(*store_); }
};

}  // namespace tessera::test
