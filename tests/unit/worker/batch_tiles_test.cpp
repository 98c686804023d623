// The tiles of the lease a worker renders: taken in order by the rendering threads, with
// more asked for before they run out, and the end of the lease once an answer adds none.
#include "worker/batch_tiles.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace tessera {
namespace {

using namespace std::chrono_literals;

std::vector<ClaimedTile> tiles(int first, int count) {
  std::vector<ClaimedTile> out;
  for (int i = first; i < first + count; ++i) out.push_back({i, TileRect{i * 8, 0, 8, 8}});
  return out;
}

using NoAnswer = std::optional<std::vector<ClaimedTile>>;

// The coordinator's side of extensions: each call waits for the test's next answer.
struct FakeCoordinator {
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<std::optional<std::vector<ClaimedTile>>> answers;
  int calls = 0;

  BatchTiles::Extend extend() {
    return [this] {
      std::unique_lock lock(mutex);
      ++calls;
      changed.notify_all();
      // Bounded, so that a test that fails before it answers still ends.
      if (!changed.wait_for(lock, 10s, [&] { return !answers.empty(); })) return NoAnswer{};
      auto answer = answers.front();
      answers.pop_front();
      return answer;
    };
  }
  void answer(std::optional<std::vector<ClaimedTile>> tiles) {
    std::lock_guard lock(mutex);
    answers.push_back(std::move(tiles));
    changed.notify_all();
  }
  int calls_made() {
    std::lock_guard lock(mutex);
    return calls;
  }
  bool wait_for_calls(int count) {
    std::unique_lock lock(mutex);
    return changed.wait_for(lock, 10s, [&] { return calls >= count; });
  }
};

std::vector<int> take_indexes(BatchTiles& batch, int count) {
  std::vector<int> indexes;
  for (int i = 0; i < count; ++i) {
    const auto taken = batch.take();
    if (!taken) break;
    indexes.push_back(taken->tile.index);
  }
  return indexes;
}

TEST(BatchTilesTest, MoreTilesAreAskedForBeforeTheyRunOutAndFollowInOrder) {
  FakeCoordinator coordinator;
  BatchTiles batch(tiles(0, 8), 2, 1, coordinator.extend());
  EXPECT_EQ(take_indexes(batch, 5), (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(coordinator.calls_made(), 0);  // three left: not yet
  EXPECT_EQ(take_indexes(batch, 1), (std::vector<int>{5}));
  // Two left, a quarter of the batch: the question goes out while they are still to render.
  ASSERT_TRUE(coordinator.wait_for_calls(1));
  EXPECT_EQ(take_indexes(batch, 2), (std::vector<int>{6, 7}));
  // Nothing left: the next take waits for the answer rather than ending the lease.
  std::thread answering([&] { coordinator.answer(tiles(8, 2)); });
  EXPECT_EQ(take_indexes(batch, 1), (std::vector<int>{8}));
  answering.join();
  ASSERT_TRUE(coordinator.wait_for_calls(2));      // 1 left of the answer's 2: asks again
  coordinator.answer(std::vector<ClaimedTile>{});  // none to add: the lease ends
  EXPECT_EQ(take_indexes(batch, 5), (std::vector<int>{9}));
  EXPECT_FALSE(batch.growing());
  EXPECT_EQ(batch.count(), 10);
  EXPECT_EQ(coordinator.calls_made(), 2);
}

// least_left() is what the worker says the threads take in an extension's round trip:
// read anew before each ask, so that fast tiles are asked for sooner than a quarter batch.
TEST(BatchTilesTest, MoreAreAskedForSoonerWhenLeastLeftSaysSo) {
  FakeCoordinator coordinator;
  std::atomic<int> least_left{1};
  BatchTiles batch(
      tiles(0, 40), [&] { return least_left.load(); }, 1, coordinator.extend());
  EXPECT_EQ(take_indexes(batch, 20).size(), 20u);
  EXPECT_EQ(coordinator.calls_made(), 0);  // 20 left: more than a quarter of 40, and than 1
  least_left = 19;
  EXPECT_EQ(take_indexes(batch, 1).size(), 1u);  // 19 left
  ASSERT_TRUE(coordinator.wait_for_calls(1));
  coordinator.answer(tiles(40, 40));
  for (int i = 0; i < 2000 && batch.count() < 80; ++i) std::this_thread::sleep_for(5ms);
  ASSERT_EQ(batch.count(), 80);
  least_left = 0;  // now a quarter of the answer's 40: 10, and no sooner
  EXPECT_EQ(take_indexes(batch, 49).size(), 49u);  // 11 left
  EXPECT_EQ(coordinator.calls_made(), 1);
  EXPECT_EQ(take_indexes(batch, 1).size(), 1u);  // 10 left
  ASSERT_TRUE(coordinator.wait_for_calls(2));
  coordinator.answer(std::vector<ClaimedTile>{});
}

TEST(BatchTilesTest, NoAnswerEndsTheLeaseWithTheTilesItHas) {
  FakeCoordinator coordinator;
  coordinator.answer(std::nullopt);  // the lease was lost, or the coordinator is unreachable
  BatchTiles batch(tiles(0, 3), 4, 1, coordinator.extend());  // asks at once
  EXPECT_EQ(take_indexes(batch, 10), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(coordinator.calls_made(), 1);
  EXPECT_EQ(batch.count(), 3);
}

TEST(BatchTilesTest, TheLastTilesAreMarkedOnceNoneWillBeAdded) {
  FakeCoordinator coordinator;
  BatchTiles batch(tiles(0, 5), 8, 2, coordinator.extend());
  ASSERT_TRUE(coordinator.wait_for_calls(1));
  const auto first = batch.take();
  ASSERT_TRUE(first);
  EXPECT_FALSE(first->among_last);  // more may still come
  coordinator.answer(std::vector<ClaimedTile>{});
  for (int i = 0; i < 1000 && batch.growing(); ++i) std::this_thread::sleep_for(5ms);
  ASSERT_FALSE(batch.growing());
  std::vector<bool> last;
  while (const auto taken = batch.take()) last.push_back(taken->among_last);
  EXPECT_EQ(last, (std::vector<bool>{false, false, true, true}));  // 3 and then 2 left: not yet
}

TEST(BatchTilesTest, TilesAddedAfterCloseAreCountedSoThatTheyCanBeGivenBack) {
  FakeCoordinator coordinator;
  BatchTiles batch(tiles(0, 2), 4, 1, coordinator.extend());
  ASSERT_TRUE(coordinator.wait_for_calls(1));
  batch.close();  // a tile failed, say
  EXPECT_FALSE(batch.take());
  coordinator.answer(tiles(2, 3));
  batch.finish();  // waits for the answer on its way
  EXPECT_EQ(batch.count(), 5);
  EXPECT_FALSE(batch.take());
}

}  // namespace
}  // namespace tessera
