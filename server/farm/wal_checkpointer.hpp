// Checkpoints a WAL-mode SQLite database from a connection and thread of its own. SQLite's
// automatic checkpoint runs inside whichever commit crosses its threshold: that commit
// then copies the WAL into the database file and waits for two fsyncs, all while the
// Scheduler's lock is held and every request waits behind it. Here the writer only notes
// the WAL's size after each commit; the copying and the fsyncs happen beside it.
#pragma once

#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>

struct sqlite3;

namespace tessera {

class WalCheckpointer {
 public:
  // Opens its own connection to `file`, which must already be in WAL mode.
  explicit WalCheckpointer(const std::filesystem::path& file);
  // Stops the thread after any checkpoint in progress, and closes its connection.
  ~WalCheckpointer();
  WalCheckpointer(const WalCheckpointer&) = delete;
  WalCheckpointer& operator=(const WalCheckpointer&) = delete;

  // The writer committed and its WAL now holds `pages`: wakes the thread once that is
  // `threshold_pages` or more. Cheap and safe from any thread.
  void wal_grew(int pages);

  // SQLite's default automatic checkpoint threshold.
  static constexpr int threshold_pages = 1000;
  // A WAL this large (32 MiB of 4 KiB pages) is restarted, briefly blocking the writer.
  static constexpr int restart_pages = 8 * threshold_pages;

 private:
  void run();

  sqlite3* db_ = nullptr;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool pending_ = false;
  bool stopping_ = false;
  std::thread thread_;  // last: it starts once everything else exists
};

}  // namespace tessera
