// The worker's upload thread: finished tiles gathered into groups, sent off the rendering
// threads, flushed before the next claim, and dropped once the coordinator refuses them.
#include "worker/tile_uploads.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
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
    return [this](int, const std::vector<FinishedTile>& group) {
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

bool eventually_sent(std::mutex& mutex,
                     const std::vector<std::pair<std::size_t, std::size_t>>& groups,
                     std::size_t count) {
  for (int i = 0; i < 2000; ++i) {
    {
      std::lock_guard lock(mutex);
      if (groups.size() >= count) return true;
    }
    std::this_thread::sleep_for(5ms);
  }
  return false;
}

TEST(TileUploadsTest, TilesReadyTogetherShareOneRequestAndFlushSendsTheRest) {
  Recorder recorder;
  // A gather long enough that the test, not the timer, decides when groups go.
  TileUploads uploads(recorder.send(), 10s, 256, 1 << 20);
  uploads.push(tile(4));
  uploads.push(tile(1));
  uploads.push(tile(3));
  EXPECT_TRUE(uploads.flush());
  EXPECT_EQ(recorder.sent(), (std::vector<std::vector<int>>{{4, 1, 3}}));
  EXPECT_TRUE(uploads.flush());  // nothing left: returns at once, sends nothing
  EXPECT_EQ(recorder.sent().size(), 1u);
}

TEST(TileUploadsTest, AGroupGoesWhenItsGatherTimeIsUpWithoutAFlush) {
  Recorder recorder;
  TileUploads uploads(recorder.send(), 20ms, 256, 1 << 20);
  uploads.push(tile(7));
  for (int i = 0; i < 500 && recorder.sent().empty(); ++i) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(recorder.sent(), (std::vector<std::vector<int>>{{7}}));
}

TEST(TileUploadsTest, GroupsStayUnderTheByteLimitButAlwaysCarryATile) {
  Recorder recorder;
  // Each tile is 12 floats = 48 bytes; 100 bytes hold two.
  TileUploads uploads(recorder.send(), 10s, 256, 100);
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

// The stall of issue 29: small tiles pile up while a group is on its way, and the next
// group took them all, past the coordinator's tile limit, which refused it.
TEST(TileUploadsTest, TilesThatPileUpDuringAnUploadNeverMakeAGroupOverEitherLimit) {
  std::mutex mutex;
  std::condition_variable released;
  bool open = false;
  std::vector<std::pair<std::size_t, std::size_t>> groups;  // tiles, bytes
  TileUploads uploads(
      [&](int, const std::vector<FinishedTile>& group) {
        std::unique_lock lock(mutex);
        std::size_t bytes = 0;
        for (const FinishedTile& t : group) bytes += t.pixels.size() * sizeof(float);
        groups.emplace_back(group.size(), bytes);
        released.wait(lock, [&] { return open; });  // the first upload is slow
        return true;
      },
      1ms, 256, 16u << 20);
  // 8x8 tiles: 768 bytes each, so bytes alone would allow 21,845 of them in one group.
  uploads.push(tile(0, 8 * 8 * 3));
  ASSERT_TRUE(eventually_sent(mutex, groups, 1));
  for (int i = 1; i <= 1365; ++i) uploads.push(tile(i, 8 * 8 * 3));
  {
    std::lock_guard lock(mutex);
    open = true;
  }
  released.notify_all();
  EXPECT_TRUE(uploads.flush());
  std::size_t total = 0;
  for (const auto& [count, bytes] : groups) {
    EXPECT_LE(count, 256u);
    EXPECT_LE(bytes, std::size_t{16} << 20);
    total += count;
  }
  EXPECT_EQ(total, 1366u);
  EXPECT_GE(groups.size(), 1u + (1365 + 255) / 256);
}

TEST(TileUploadsTest, WithTwoSendersTheNextGroupGoesWhileOneWaitsForItsAnswer) {
  std::mutex mutex;
  std::condition_variable changed;
  bool open = false;
  std::vector<int> in_flight_by_sender(2, 0);
  int in_flight = 0;
  int most_in_flight = 0;
  std::vector<int> sent;
  TileUploads uploads(
      [&](int sender, const std::vector<FinishedTile>& group) {
        std::unique_lock lock(mutex);
        EXPECT_EQ(in_flight_by_sender.at(sender)++, 0)
            << "sender " << sender << " used twice at once";
        most_in_flight = std::max(most_in_flight, ++in_flight);
        for (const FinishedTile& t : group) sent.push_back(t.index);
        changed.notify_all();
        // The first answer is slow: it comes once the second group is on its way too (or,
        // should that never happen, after a while, so that the test still ends).
        changed.wait_for(lock, 5s, [&] { return open || in_flight == 2; });
        open = true;
        --in_flight;
        --in_flight_by_sender[sender];
        changed.notify_all();
        return true;
      },
      1ms, 2, 1 << 20, 2);
  for (int i = 0; i < 6; ++i) uploads.push(tile(i));
  EXPECT_TRUE(uploads.flush());
  std::lock_guard lock(mutex);
  EXPECT_EQ(most_in_flight, 2);
  std::sort(sent.begin(), sent.end());
  EXPECT_EQ(sent, (std::vector<int>{0, 1, 2, 3, 4, 5}));  // each once
}

TEST(TileUploadsTest, GroupsKeepToBothLimitsWhicheverComesFirst) {
  Recorder recorder;
  // 10 floats = 40 bytes a tile: 4 tiles by count, or 2 by bytes (100).
  TileUploads uploads(recorder.send(), 10s, 4, 1 << 20);
  for (int i = 0; i < 10; ++i) uploads.push(tile(i, 10));
  EXPECT_TRUE(uploads.flush());
  for (const auto& group : recorder.sent()) EXPECT_LE(group.size(), 4u);
  uploads.set_limits(256, 100);
  for (int i = 10; i < 20; ++i) uploads.push(tile(i, 10));
  EXPECT_TRUE(uploads.flush());
  const auto sent = recorder.sent();
  std::size_t after = 0;
  for (const auto& group : sent)
    if (group.front() >= 10) {
      EXPECT_LE(group.size(), 2u);
      after += group.size();
    }
  EXPECT_EQ(after, 10u);
}

TEST(TileUploadsTest, AfterSendPromptlyTilesGoWithoutWaitingForTheGatherUntilTheFlush) {
  Recorder recorder;
  // A gather far longer than the waits below: only send_promptly() can make these go.
  TileUploads uploads(recorder.send(), 60s, 256, 1 << 20);
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

TEST(TileUploadsTest, ARefusalDropsTheLeasesLaterTilesUntilTheFlush) {
  Recorder recorder;
  recorder.refuse = true;
  // A group per tile (one tile fills the byte limit), so each goes as soon as it is pushed.
  TileUploads uploads(recorder.send(), 10s, 256, 3 * sizeof(float));
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
