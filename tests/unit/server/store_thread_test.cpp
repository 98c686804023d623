// The store thread: writes queued while it is busy are committed together and in order, a
// write the store refuses fails alone, callbacks never run on the thread that gives them,
// and reads see every write queued before them.
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/server/test_dir.hpp"

#include "server/farm/sqlite_store.hpp"
#include "server/farm/store_thread.hpp"

namespace tessera {
namespace {

class StoreThreadTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::fresh_test_dir("tessera-store-thread-test");
    store_ = std::make_unique<SqliteStore>(dir_);
  }
  void TearDown() override {
    store_.reset();
    std::filesystem::remove_all(dir_);
  }

  static StoreThread::Work add_worker(const std::string& id) {
    return [id](Store& store) { store.upsert_worker({id, "name", "host", 1, "idle", 0, 0, ""}); };
  }
  std::vector<std::string> stored_workers() {
    std::vector<std::string> ids;
    for (const WorkerRow& row : store_->load().workers) ids.push_back(row.id);
    std::sort(ids.begin(), ids.end());
    return ids;
  }

  std::filesystem::path dir_;
  std::unique_ptr<SqliteStore> store_;
};

TEST_F(StoreThreadTest, WritesQueuedWhileItIsBusyCommitInOneTransactionInOrder) {
  std::vector<std::string> told;
  {
    StoreThread thread(*store_);
    // The first write holds the thread until the others are queued behind it.
    std::promise<void> release;
    std::shared_future<void> released = release.get_future().share();
    std::promise<void> started;
    thread.write([&, released](Store& store) {
      started.set_value();
      released.wait();
      add_worker("w-0")(store);
    });
    started.get_future().wait();
    StoreTicket last = 0;
    for (int i = 1; i <= 9; ++i) {
      last = thread.write(add_worker("w-" + std::to_string(i)));
      thread.after(last, [&told, i](const std::string& error) {
        told.push_back(std::to_string(i) + (error.empty() ? "" : " refused"));
      });
    }
    release.set_value();
    EXPECT_EQ(thread.wait(last), "");
    EXPECT_EQ(thread.transactions(), 2u) << "the nine queued writes were not grouped";
  }
  EXPECT_EQ(told, (std::vector<std::string>{"1", "2", "3", "4", "5", "6", "7", "8", "9"}));
  EXPECT_EQ(stored_workers().size(), 10u);
}

TEST_F(StoreThreadTest, AWriteTheStoreRefusesFailsAloneAndSaysWhy) {
  StoreThread thread(*store_);
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::promise<void> started;
  thread.write([&, released](Store&) {
    started.set_value();
    released.wait();
  });
  started.get_future().wait();
  const StoreTicket before = thread.write(add_worker("w-before"));
  const StoreTicket refused =
      thread.write([](Store&) { throw std::runtime_error("the disk is full"); });
  const StoreTicket after = thread.write(add_worker("w-after"));
  release.set_value();
  EXPECT_EQ(thread.wait(before), "");
  EXPECT_EQ(thread.wait(refused), "the disk is full");
  EXPECT_EQ(thread.wait(after), "");
  // Told again to a callback given after the fact.
  std::promise<std::string> late;
  thread.after(refused, [&](const std::string& error) { late.set_value(error); });
  EXPECT_EQ(late.get_future().get(), "the disk is full");
  EXPECT_EQ(stored_workers(), (std::vector<std::string>{"w-after", "w-before"}));
}

TEST_F(StoreThreadTest, CallbacksRunOnTheStoreThreadEvenWhenTheWriteIsDurableAlready) {
  StoreThread thread(*store_);
  const StoreTicket ticket = thread.write(add_worker("w-1"));
  EXPECT_EQ(thread.wait(ticket), "");
  // The caller holds a lock the callback takes: run here, it would deadlock.
  std::mutex mutex;
  std::promise<std::thread::id> ran_on;
  {
    std::lock_guard lock(mutex);
    thread.after(ticket, [&](const std::string&) {
      std::lock_guard inner(mutex);
      ran_on.set_value(std::this_thread::get_id());
    });
  }
  EXPECT_NE(ran_on.get_future().get(), std::this_thread::get_id());
}

TEST_F(StoreThreadTest, AReadSeesEveryWriteQueuedBeforeIt) {
  StoreThread thread(*store_);
  for (int i = 0; i < 50; ++i) thread.write(add_worker("w-" + std::to_string(100 + i)));
  std::size_t seen = 0;
  thread.call([&](Store& store) { seen = store.load().workers.size(); });
  EXPECT_EQ(seen, 50u);
}

TEST_F(StoreThreadTest, DestroyingItFinishesWhatIsQueuedAndTellsEveryCallback) {
  std::atomic<int> told{0};
  {
    StoreThread thread(*store_);
    for (int i = 0; i < 20; ++i) {
      const StoreTicket ticket = thread.write(add_worker("w-" + std::to_string(i)));
      thread.after(ticket, [&](const std::string& error) {
        if (error.empty()) ++told;
      });
    }
  }
  EXPECT_EQ(told.load(), 20);
  EXPECT_EQ(stored_workers().size(), 20u);
}

}  // namespace
}  // namespace tessera
