// What a failed write leaves behind: after any failure, however far the transaction got,
// the connection is back in autocommit, nothing of the failed change is stored, and what
// is committed after it is durable, as another connection (the next coordinator's) reads
// it. The faults come from a VFS that fails writes as a full disk does.
#include <filesystem>
#include <future>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "server/farm/sqlite_db.hpp"
#include "server/farm/sqlite_store.hpp"
#include "server/farm/store_error.hpp"
#include "server/farm/store_thread.hpp"
#include "tests/unit/server/faulty_vfs.hpp"
#include "tests/unit/server/test_dir.hpp"

namespace tessera {
namespace {

using test::FaultyVfs;

class StoreFaultsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::fresh_test_dir("tessera-store-faults-test");
    std::filesystem::create_directories(dir_);
    db_ = std::make_unique<SqliteDb>(
        file(), std::vector<std::string>{"PRAGMA journal_mode=WAL", "PRAGMA foreign_keys=ON"});
    db_->exec("CREATE TABLE rows (x INTEGER, filler BLOB)");
  }
  void TearDown() override {
    db_.reset();
    std::filesystem::remove_all(dir_);
  }
  std::filesystem::path file() const { return dir_ / "test.db"; }

  void insert(int x, int filler_bytes = 0) {
    db_->statement("INSERT INTO rows (x, filler) VALUES (?, zeroblob(?))")
        ->bind(1, x)
        .bind(2, filler_bytes)
        .run();
  }
  // The rows as a connection of its own reads them: what is durable.
  std::string stored() const {
    return SqliteDb(file()).query_text("SELECT coalesce(group_concat(x, ','), '') FROM rows");
  }

  std::filesystem::path dir_;
  FaultyVfs vfs_;  // before the connection, which opens through it
  std::unique_ptr<SqliteDb> db_;
};

TEST_F(StoreFaultsTest, ACommitTheDiskRefusesIsRolledBackWholeAndTheNextOneIsDurable) {
  {
    Transaction tx(*db_);
    insert(1);
    vfs_.arm(FaultyVfs::Fails::writes, SQLITE_FULL);
    try {
      tx.commit();
      FAIL() << "committed on a full disk";
    } catch (const StoreError& e) {
      EXPECT_EQ(e.fault(), StoreFault::disk_full) << e.what();
      EXPECT_NE(std::string(e.what()).find("the disk is full"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(db_->in_transaction());
  }
  EXPECT_FALSE(db_->in_transaction());
  vfs_.disarm();
  {
    Transaction tx(*db_);
    insert(2);
    tx.commit();
  }
  EXPECT_FALSE(db_->in_transaction());
  EXPECT_EQ(stored(), "2");
}

TEST_F(StoreFaultsTest, AChangeAbandonedOnAFullDiskLeavesNoTransactionOpen) {
  // As a work item whose pixel file is refused: rows written, then an exception. Rolling
  // back to the savepoint and releasing it commits what is left, which the still full disk
  // refuses; the transaction then stayed open, and every later one nested inside it.
  {
    Transaction tx(*db_);
    insert(1);
    vfs_.arm(FaultyVfs::Fails::writes, SQLITE_FULL);
  }
  EXPECT_FALSE(db_->in_transaction());
  // Still full: another change fails too, and leaves nothing open either.
  EXPECT_THROW(
      {
        Transaction tx(*db_);
        insert(2);
        tx.commit();
      },
      StoreError);
  EXPECT_FALSE(db_->in_transaction());
  vfs_.disarm();
  for (int x = 3; x <= 4; ++x) {
    Transaction tx(*db_);
    insert(x);
    tx.commit();
  }
  EXPECT_EQ(stored(), "3,4");
  EXPECT_GT(vfs_.failed(), 0);
}

TEST_F(StoreFaultsTest, NestedChangesOnAFullDiskLeaveNothingOpen) {
  {
    Transaction outer(*db_);
    insert(1);
    {
      Transaction inner(*db_);
      insert(2);
      vfs_.arm(FaultyVfs::Fails::writes, SQLITE_FULL);
    }  // the inner one abandoned: its savepoint is rolled back, in memory
    EXPECT_TRUE(db_->in_transaction());
    EXPECT_THROW(outer.commit(), StoreError);
  }
  EXPECT_FALSE(db_->in_transaction());
  vfs_.disarm();
  {
    Transaction tx(*db_);
    insert(3);
    tx.commit();
  }
  EXPECT_EQ(stored(), "3");
}

TEST_F(StoreFaultsTest,
       AStatementAfterSqliteRolledTheTransactionBackFailsInsteadOfCommittingAlone) {
  // A tiny page cache makes a large row spill to the WAL mid-statement: on a full disk
  // SQLite then rolls the whole transaction back by itself.
  db_->exec("PRAGMA cache_size=2");
  Transaction tx(*db_);
  insert(1);
  vfs_.arm(FaultyVfs::Fails::writes, SQLITE_FULL);
  EXPECT_THROW(insert(2, 4 << 20), StoreError);
  vfs_.disarm();
  if (db_->in_transaction()) GTEST_SKIP() << "this SQLite kept the transaction after the failure";
  // A caller that went on regardless would store row 3 without row 1.
  EXPECT_THROW(insert(3), StoreError);
  EXPECT_THROW(tx.commit(), StoreError);
  EXPECT_FALSE(db_->in_transaction());
  EXPECT_EQ(stored(), "");
}

TEST_F(StoreFaultsTest, AFailedWriteOrCheckpointLosesNothingCommittedAndLeavesNothingOpen) {
  {
    Transaction tx(*db_);
    insert(1);
    tx.commit();
  }
  for (const int code : {SQLITE_IOERR_WRITE, SQLITE_FULL}) {
    vfs_.arm(FaultyVfs::Fails::writes, code);
    EXPECT_THROW(
        {
          Transaction tx(*db_);
          insert(9);
          tx.commit();
        },
        StoreError);
    vfs_.disarm();
    EXPECT_FALSE(db_->in_transaction());
  }
  // A checkpoint whose sync fails copies nothing for good: the WAL still holds row 1.
  vfs_.arm(FaultyVfs::Fails::syncs, SQLITE_IOERR_FSYNC);
  EXPECT_THROW(db_->exec("PRAGMA wal_checkpoint(TRUNCATE)"), StoreError);
  vfs_.disarm();
  EXPECT_FALSE(db_->in_transaction());
  {
    Transaction tx(*db_);
    insert(2);
    tx.commit();
  }
  EXPECT_EQ(stored(), "1,2");
  db_->exec("PRAGMA wal_checkpoint(TRUNCATE)");
  EXPECT_EQ(stored(), "1,2");
}

TEST_F(StoreFaultsTest, AConnectionReopenedEndsItsTransactionAndSetsItUpAgain) {
  db_->exec("BEGIN");
  insert(1);
  ASSERT_TRUE(db_->in_transaction());
  db_->reopen();
  EXPECT_FALSE(db_->in_transaction());
  EXPECT_EQ(db_->query_text("PRAGMA foreign_keys"), "1");
  EXPECT_EQ(db_->query_text("PRAGMA journal_mode"), "wal");
  Transaction tx(*db_);
  insert(2);
  tx.commit();
  EXPECT_EQ(stored(), "2");
}

// The store thread over a real Store: the full disk, its space back, and a write.
class StoreThreadFaultsTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::fresh_test_dir("tessera-store-thread-faults-test"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  static StoreThread::Work add_worker(const std::string& id) {
    return [id](Store& store) { store.upsert_worker({id, "name", "host", 1, "idle", 0, 0, ""}); };
  }
  std::vector<std::string> stored_workers() {
    SqliteStore store(dir_);
    std::vector<std::string> ids;
    for (const WorkerRow& row : store.load().workers) ids.push_back(row.id);
    std::sort(ids.begin(), ids.end());
    return ids;
  }

  std::filesystem::path dir_;
  FaultyVfs vfs_;
};

TEST_F(StoreThreadFaultsTest, AfterAFullDiskRefusedAWriteTheNextWritesAreStoredAgain) {
  {
    SqliteStore store(dir_);
    StoreThread thread(store);
    // A write that dirties pages and then fails, as an upload whose pixel file the full
    // disk refuses does; the disk stays full while it is rolled back.
    vfs_.arm(FaultyVfs::Fails::writes, SQLITE_FULL);
    const std::string refused = thread.wait(thread.write([](Store& store) {
      add_worker("w-lost")(store);
      throw StoreError(StoreFault::disk_full, "store: cannot write the pixels: the disk is full");
    }));
    EXPECT_NE(refused.find("the disk is full"), std::string::npos) << refused;
    EXPECT_NE(thread.wait(thread.write(add_worker("w-also-lost"))), "");
    vfs_.disarm();  // space back
    EXPECT_EQ(thread.wait(thread.write(add_worker("w-1"))), "");
    EXPECT_EQ(thread.wait(thread.write(add_worker("w-2"))), "");
    // Read by another connection while this one stays open and idle.
    EXPECT_EQ(stored_workers(), (std::vector<std::string>{"w-1", "w-2"}));
  }
  EXPECT_EQ(stored_workers(), (std::vector<std::string>{"w-1", "w-2"}));
}

TEST_F(StoreThreadFaultsTest, AShortageThatPassesIsWaitedOutAndFailsNothing) {
  SqliteStore store(dir_);
  StoreThread thread(store);
  int tries = 0;
  // No descriptor left for the first three tries (EMFILE), as under a flood of connections.
  const StoreTicket first = thread.write([&](Store& store) {
    add_worker("w-1")(store);
    if (++tries <= 3)
      throw StoreError(StoreFault::transient, "store: cannot open x: Too many open files");
  });
  const StoreTicket second = thread.write(add_worker("w-2"));
  EXPECT_EQ(thread.wait(first), "");
  EXPECT_EQ(thread.wait(second), "");
  EXPECT_EQ(tries, 4);
  EXPECT_EQ(stored_workers(), (std::vector<std::string>{"w-1", "w-2"}));
}

TEST(StoreErrorsTest, ErrnosNameTheirFault) {
  EXPECT_EQ(fault_of_errno(ENOSPC), StoreFault::disk_full);
  EXPECT_EQ(fault_of_errno(EDQUOT), StoreFault::disk_full);
  EXPECT_EQ(fault_of_errno(EMFILE), StoreFault::transient);
  EXPECT_EQ(fault_of_errno(ENFILE), StoreFault::transient);
  EXPECT_EQ(fault_of_errno(EIO), StoreFault::other);
  EXPECT_NE(errno_words(ENOSPC).find("the disk is full"), std::string::npos);
  EXPECT_EQ(errno_words(EIO).find("the disk is full"), std::string::npos);
  EXPECT_EQ(fault_of(std::runtime_error("x")), StoreFault::other);
  EXPECT_EQ(fault_of(StoreError(StoreFault::transient, "x")), StoreFault::transient);
}

}  // namespace
}  // namespace tessera
