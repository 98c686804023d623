#include "server/farm/sqlite_db.hpp"

#include <spdlog/spdlog.h>
#include <sqlite3.h>

#include "server/farm/store_error.hpp"

namespace tessera {
namespace {

// Long enough to ride out another process's checkpoint or a backup tool's read; short
// enough that a wedged database shows up as an error instead of a hang.
constexpr int busy_timeout_ms = 5000;

// The error of a failed call on `db` that returned `rc`: its fault, and SQLite's words
// with, for a failed file operation, the system's ("disk I/O error" alone would not say
// that the disk is full).
StoreError sqlite_error(sqlite3* db, int rc, const std::string& what, const std::string& sql) {
  // The connection's message is its last call's; where that is not this one (an error
  // returned before SQLite recorded it), the code's own words are truer.
  std::string message = !db                                           ? "out of memory"
                        : (sqlite3_errcode(db) & 0xff) == (rc & 0xff) ? sqlite3_errmsg(db)
                                                                      : sqlite3_errstr(rc);
  StoreFault fault = StoreFault::other;
  const int primary = rc & 0xff;
  const int system = db ? sqlite3_system_errno(db) : 0;
  if (primary == SQLITE_FULL) {
    fault = StoreFault::disk_full;
    message = "the disk is full (" + message + ")";
  } else if (primary == SQLITE_BUSY || primary == SQLITE_LOCKED || primary == SQLITE_NOMEM) {
    fault = StoreFault::transient;
  } else if ((primary == SQLITE_IOERR || primary == SQLITE_CANTOPEN) && system != 0) {
    fault = fault_of_errno(system);
    message += ": " + errno_words(system);
  }
  std::string text = "sqlite: " + what + " failed: " + message;
  if (!sql.empty()) text += " [" + sql + "]";
  return StoreError(fault, text);
}

}  // namespace

Statement::Statement(sqlite3* db, std::string_view sql) : sql_(sql) {
  const int rc = sqlite3_prepare_v3(db, sql.data(), static_cast<int>(sql.size()),
                                    SQLITE_PREPARE_PERSISTENT, &stmt_, nullptr);
  if (rc != SQLITE_OK) throw sqlite_error(db, rc, "prepare", sql_);
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

void Statement::fail(std::string_view what, int rc) const {
  throw sqlite_error(sqlite3_db_handle(stmt_), rc, std::string(what), sql_);
}

Statement& Statement::bind(int index, std::int64_t value) {
  if (const int rc = sqlite3_bind_int64(stmt_, index, value); rc != SQLITE_OK) fail("bind", rc);
  return *this;
}

Statement& Statement::bind(int index, std::string_view text) {
  // A null pointer would bind SQL NULL; the schema wants "" for "none".
  const char* data = text.data() ? text.data() : "";
  if (const int rc =
          sqlite3_bind_text(stmt_, index, data, static_cast<int>(text.size()), SQLITE_TRANSIENT);
      rc != SQLITE_OK)
    fail("bind", rc);
  return *this;
}

Statement& Statement::bind_view(int index, std::string_view text) {
  const char* data = text.data() ? text.data() : "";
  if (const int rc =
          sqlite3_bind_text64(stmt_, index, data, text.size(), SQLITE_STATIC, SQLITE_UTF8);
      rc != SQLITE_OK)
    fail("bind", rc);
  return *this;
}

Statement& Statement::bind_blob(int index, std::span<const std::byte> bytes) {
  // SQLITE_STATIC: tiles can be large, and the caller's buffer outlives the statement's
  // use (bindings are cleared by reset()).
  const int rc = bytes.empty()
                     ? sqlite3_bind_zeroblob(stmt_, index, 0)
                     : sqlite3_bind_blob64(stmt_, index, bytes.data(), bytes.size(), SQLITE_STATIC);
  if (rc != SQLITE_OK) fail("bind", rc);
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  fail("step", rc);
}

void Statement::run() {
  while (step()) {
  }
}

std::int64_t Statement::column_int64(int index) const { return sqlite3_column_int64(stmt_, index); }

std::string Statement::column_text(int index) const {
  const auto* text = sqlite3_column_text(stmt_, index);
  if (!text) return {};
  return std::string(reinterpret_cast<const char*>(text),
                     static_cast<std::size_t>(sqlite3_column_bytes(stmt_, index)));
}

std::span<const std::byte> Statement::column_blob(int index) const {
  const void* data = sqlite3_column_blob(stmt_, index);
  if (!data) return {};
  return {static_cast<const std::byte*>(data),
          static_cast<std::size_t>(sqlite3_column_bytes(stmt_, index))};
}

void Statement::reset() {
  // reset() repeats the last step's error code, which was already reported.
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

SqliteDb::SqliteDb(const std::filesystem::path& file, std::vector<std::string> setup)
    : file_(file), setup_(std::move(setup)) {
  open();
}

SqliteDb::~SqliteDb() {
  // The checkpointer's connection closes first, so that this one, the last, checkpoints
  // the whole WAL on close.
  checkpointer_.reset();
  close();
}

void SqliteDb::open() {
  const int rc =
      sqlite3_open_v2(file_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  if (rc != SQLITE_OK) {
    const StoreError error = sqlite_error(db_, rc, "opening " + file_.string(), "");
    sqlite3_close(db_);
    db_ = nullptr;
    throw error;
  }
  sqlite3_extended_result_codes(db_, 1);
  sqlite3_busy_timeout(db_, busy_timeout_ms);
  try {
    for (const std::string& sql : setup_) exec(sql);
  } catch (...) {
    close();
    throw;
  }
  if (checkpointer_) {
    exec("PRAGMA wal_autocheckpoint=0");
    sqlite3_wal_hook(db_, &SqliteDb::on_wal_commit, this);
  }
}

void SqliteDb::close() {
  // Unfinalized statements would make close fail.
  statements_.clear();
  sqlite3_close(db_);
  db_ = nullptr;
}

void SqliteDb::reopen() {
  spdlog::warn("sqlite: reopening {}: a transaction stayed open after its rollback",
               file_.string());
  close();  // rolls back whatever the connection still held
  open();
}

bool SqliteDb::in_transaction() const { return db_ && sqlite3_get_autocommit(db_) == 0; }

void SqliteDb::end_transaction() noexcept {
  if (!in_transaction()) return;
  // ROLLBACK undoes the whole transaction without writing (the WAL's uncommitted frames
  // are simply forgotten); ROLLBACK TO and RELEASE would commit what remains, which a
  // full disk can refuse again, leaving the transaction open and every later one nested
  // inside it, never to commit.
  char* message = nullptr;
  if (sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, &message) != SQLITE_OK) {
    spdlog::warn("sqlite: ROLLBACK failed: {}", message ? message : sqlite3_errmsg(db_));
    sqlite3_free(message);
  }
  if (!in_transaction()) return;
  try {
    reopen();
  } catch (const std::exception& e) {
    // Every later call fails, naming the connection; nothing is answered as stored.
    spdlog::error("sqlite: cannot reopen {}: {}", file_.string(), e.what());
  }
}

void SqliteDb::checkpoint_in_background() {
  checkpointer_ = std::make_unique<WalCheckpointer>(file_);
  exec("PRAGMA wal_autocheckpoint=0");
  sqlite3_wal_hook(db_, &SqliteDb::on_wal_commit, this);
}

int SqliteDb::on_wal_commit(void* self, sqlite3* db, const char* name, int pages) {
  auto& owner = *static_cast<SqliteDb*>(self);
  owner.checkpointer_->wal_grew(pages);
  // Far behind (a reader held it back, or the disk is slow): what SQLite's own automatic
  // checkpoint would have done, in this commit.
  if (pages >= 8 * WalCheckpointer::restart_pages)
    sqlite3_wal_checkpoint_v2(db, name, SQLITE_CHECKPOINT_PASSIVE, nullptr, nullptr);
  return SQLITE_OK;
}

void SqliteDb::exec(std::string_view sql) {
  const std::string text(sql);
  if (!db_) throw StoreError(StoreFault::other, "sqlite: " + file_.string() + " is not open");
  char* error = nullptr;
  if (const int rc = sqlite3_exec(db_, text.c_str(), nullptr, nullptr, &error); rc != SQLITE_OK) {
    sqlite3_free(error);  // sqlite3_errmsg says the same
    throw sqlite_error(db_, rc, "exec", text);
  }
}

StatementUse SqliteDb::statement(std::string_view sql) {
  if (!db_) throw StoreError(StoreFault::other, "sqlite: " + file_.string() + " is not open");
  // Inside a Transaction that SQLite has rolled back on its own, a statement would commit
  // alone: the part of a change after the failure stored without the part before.
  if (depth_ > 0 && !in_transaction())
    throw StoreError(StoreFault::other,
                     "sqlite: the transaction was rolled back after an earlier failure");
  auto it = statements_.find(std::string(sql));
  if (it == statements_.end())
    it = statements_.emplace(std::string(sql), std::make_unique<Statement>(db_, sql)).first;
  return StatementUse(*it->second);
}

std::string SqliteDb::query_text(std::string_view sql) {
  Statement statement(db_, sql);
  return statement.step() ? statement.column_text(0) : std::string();
}

// SAVEPOINT and RELEASE run on every state change: prepared once, not compiled each time.
Transaction::Transaction(SqliteDb& db) : db_(db), outermost_(db.depth_ == 0) {
  // Never inside a transaction left open: what this one commits would not be committed.
  if (outermost_) db_.end_transaction();
  db_.statement("SAVEPOINT tessera_tx")->step();
  ++db_.depth_;
}

Transaction::~Transaction() {
  if (!open_) return;
  --db_.depth_;
  if (outermost_) {
    db_.end_transaction();
    return;
  }
  try {
    db_.exec("ROLLBACK TO tessera_tx");
    db_.exec("RELEASE tessera_tx");
  } catch (...) {
    // A destructor must not throw. SQLite rolled the whole transaction back already (no
    // such savepoint), or the outermost Transaction rolls it back as it ends.
  }
}

void Transaction::commit() {
  // Whatever happens below, this Transaction is over: the destructor has nothing to undo
  // but what end_transaction() undoes.
  open_ = false;
  --db_.depth_;
  try {
    db_.statement("RELEASE tessera_tx")->step();
  } catch (...) {
    if (outermost_) db_.end_transaction();
    throw;
  }
  if (outermost_ && db_.in_transaction()) {
    db_.end_transaction();
    throw StoreError(StoreFault::other, "sqlite: the commit left a transaction open");
  }
}

}  // namespace tessera
