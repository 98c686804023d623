// The worker's upload thread: finished tiles gathered into groups, sent off the rendering
// threads, flushed before the next claim, and dropped once the coordinator refuses them.
#include "worker/tile_uploads.hpp"

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace tessera {
namespace {

using namespace std::chrono_literals;

FinishedTile tile(int index, std::size_t floats = 3) {
  return FinishedTile{index, std::vector<float>(floats, static_cast<float>(index)), 10u};
}

// Records what would have gone to the coordinator.
struct Recorder {
  std::mutex mutex;
  std::vector<std::vector<int>> groups;
  std::atomic<bool> refuse{false};

  TileUploads::Send send() {
    return [this](const std::vector<FinishedTile>& group) {
      std::lock_guard lock(mutex);
      std::vector<int> indexes;
      for (const FinishedTile& t : group) indexes.push_back(t.index);
      groups.push_back(indexes);
      return !refuse;
    };
  }
  std::vector<std::vector<int>> sent() {
    std::lock_guard lock(mutex);
    return groups;
  }
};

TEST(TileUploads, TilesReadyTogetherShareOneRequestAndFlushSendsTheRest) {
  Recorder recorder;
  // A gather long enough that the test, not the timer, decides when groups go.
  TileUploads uploads(recorder.send(), 10s, 1 << 20);
  uploads.push(tile(4));
  uploads.push(tile(1));
  uploads.push(tile(3));
  EXPECT_TRUE(uploads.flush());
  EXPECT_EQ(recorder.sent(), (std::vector<std::vector<int>>{{4, 1, 3}}));
  EXPECT_TRUE(uploads.flush());  // nothing left: returns at once, sends nothing
  EXPECT_EQ(recorder.sent().size(), 1u);
}

TEST(TileUploads, AGroupGoesWhenItsGatherTimeIsUpWithoutAFlush) {
  Recorder recorder;
  TileUploads uploads(recorder.send(), 20ms, 1 << 20);
  uploads.push(tile(7));
  for (int i = 0; i < 500 && recorder.sent().empty(); ++i) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(recorder.sent(), (std::vector<std::vector<int>>{{7}}));
}

TEST(TileUploads, GroupsStayUnderTheByteLimitButAlwaysCarryATile) {
  Recorder recorder;
  // Each tile is 12 floats = 48 bytes; 100 bytes hold two.
  TileUploads uploads(recorder.send(), 10s, 100);
  for (int i = 0; i < 5; ++i) uploads.push(tile(i, 12));
  uploads.push(tile(9, 1000));  // larger than the limit alone
  EXPECT_TRUE(uploads.flush());
  std::vector<int> order;
  for (const auto& group : recorder.sent()) {
    EXPECT_FALSE(group.empty());
    std::size_t bytes = 0;
    for (const int index : group) bytes += (index == 9 ? 1000 : 12) * sizeof(float);
    if (group.size() > 1) {
      EXPECT_LE(bytes, 100u);
    }
    order.insert(order.end(), group.begin(), group.end());
  }
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4, 9}));
}

TEST(TileUploads, AfterSendPromptlyTilesGoWithoutWaitingForTheGatherUntilTheFlush) {
  Recorder recorder;
  // A gather far longer than the waits below: only send_promptly() can make these go.
  TileUploads uploads(recorder.send(), 60s, 1 << 20);
  const auto wait_for_groups = [&](std::size_t count) {
    for (int i = 0; i < 500 && recorder.sent().size() < count; ++i)
      std::this_thread::sleep_for(10ms);
  };
  uploads.push(tile(1));
  uploads.send_promptly();
  wait_for_groups(1);
  EXPECT_EQ(recorder.sent(), (std::vector<std::vector<int>>{{1}}));
  uploads.push(tile(2));  // pushed after the call: goes as soon as it is ready
  wait_for_groups(2);
  EXPECT_EQ(recorder.sent(), (std::vector<std::vector<int>>{{1}, {2}}));
  EXPECT_TRUE(uploads.flush());

  // The flush ends it: the next lease's tiles are gathered again, and wait for the flush.
  uploads.push(tile(3));
  uploads.push(tile(4));
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(recorder.sent().size(), 2u);
  EXPECT_TRUE(uploads.flush());
  EXPECT_EQ(recorder.sent().back(), (std::vector<int>{3, 4}));
}

TEST(TileUploads, ARefusalDropsTheLeasesLaterTilesUntilTheFlush) {
  Recorder recorder;
  recorder.refuse = true;
  // A group per tile (one tile fills the byte limit), so each goes as soon as it is pushed.
  TileUploads uploads(recorder.send(), 10s, 3 * sizeof(float));
  uploads.push(tile(1));
  for (int i = 0; i < 500 && !uploads.refused(); ++i) std::this_thread::sleep_for(10ms);
  ASSERT_TRUE(uploads.refused());
  uploads.push(tile(2));
  uploads.push(tile(3));
  EXPECT_FALSE(uploads.flush());
  EXPECT_EQ(recorder.sent(), (std::vector<std::vector<int>>{{1}}));  // 2 and 3 dropped
  EXPECT_FALSE(uploads.refused());  // flush() reported it and cleared it

  recorder.refuse = false;
  uploads.push(tile(4));  // the next lease starts clean
  EXPECT_TRUE(uploads.flush());
  EXPECT_EQ(recorder.sent().back(), (std::vector<int>{4}));
}

}  // namespace
}  // namespace tessera
