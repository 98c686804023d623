#include "server/farm/wal_checkpointer.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <stdexcept>
#include <string>

#include <spdlog/spdlog.h>
#include <sqlite3.h>

namespace tessera {

WalCheckpointer::WalCheckpointer(const std::filesystem::path& file) {
  if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw std::runtime_error("sqlite: cannot open " + file.string() + " to checkpoint: " + message);
  }
  // As the writer's: in WAL mode NORMAL syncs at checkpoints, which is all this one does.
  sqlite3_exec(db_, "PRAGMA synchronous=NORMAL", nullptr, nullptr, nullptr);
  // A restarting checkpoint waits this long for the writer to finish its transaction.
  sqlite3_busy_timeout(db_, 1000);
  thread_ = std::thread([this] { run(); });
}

WalCheckpointer::~WalCheckpointer() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
  sqlite3_close(db_);
}

void WalCheckpointer::wal_grew(int pages) {
  if (pages < threshold_pages) return;
  {
    std::lock_guard lock(mutex_);
    if (pending_) return;
    pending_ = true;
  }
  wake_.notify_one();
}

void WalCheckpointer::run() {
  // Below the threads that answer requests: the WAL may grow a little meanwhile.
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 5);
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || pending_; });
    if (stopping_) return;
    pending_ = false;
    lock.unlock();
    // PASSIVE copies what the WAL holds and never waits for the writer, which goes on
    // committing meanwhile. Once everything is copied, the writer's next transaction
    // starts the WAL over from its beginning. Under steady load that moment may not come
    // (each commit lands while the last ones are copied), so a WAL that has grown large
    // is restarted: RESTART blocks the writer while it copies the little that arrived
    // since the passive pass, syncs, and resets.
    int wal_pages = 0;
    int rc =
        sqlite3_wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_PASSIVE, &wal_pages, nullptr);
    if (rc == SQLITE_OK && wal_pages >= restart_pages)
      rc = sqlite3_wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_RESTART, nullptr, nullptr);
    if (rc != SQLITE_OK && rc != SQLITE_BUSY)
      spdlog::warn("sqlite: checkpoint failed: {}", sqlite3_errmsg(db_));
    lock.lock();
  }
}

}  // namespace tessera
