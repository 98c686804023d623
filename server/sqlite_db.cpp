#include "server/sqlite_db.hpp"

#include <stdexcept>

#include <sqlite3.h>

namespace tessera {
namespace {

// Long enough to ride out another process's checkpoint or a backup tool's read; short
// enough that a wedged database shows up as an error instead of a hang.
constexpr int busy_timeout_ms = 5000;

std::string errmsg_of(sqlite3* db) { return db ? sqlite3_errmsg(db) : "out of memory"; }

}  // namespace

Statement::Statement(sqlite3* db, std::string_view sql) : sql_(sql) {
  if (sqlite3_prepare_v3(db, sql.data(), static_cast<int>(sql.size()), SQLITE_PREPARE_PERSISTENT,
                         &stmt_, nullptr) != SQLITE_OK) {
    throw std::runtime_error("sqlite: prepare failed: " + errmsg_of(db) + " [" + sql_ + "]");
  }
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

void Statement::fail(std::string_view what) const {
  throw std::runtime_error("sqlite: " + std::string(what) +
                           " failed: " + errmsg_of(sqlite3_db_handle(stmt_)) + " [" + sql_ + "]");
}

Statement& Statement::bind(int index, std::int64_t value) {
  if (sqlite3_bind_int64(stmt_, index, value) != SQLITE_OK) fail("bind");
  return *this;
}

Statement& Statement::bind(int index, std::string_view text) {
  // A null pointer would bind SQL NULL; the schema wants "" for "none".
  const char* data = text.data() ? text.data() : "";
  if (sqlite3_bind_text(stmt_, index, data, static_cast<int>(text.size()), SQLITE_TRANSIENT) !=
      SQLITE_OK)
    fail("bind");
  return *this;
}

Statement& Statement::bind_view(int index, std::string_view text) {
  const char* data = text.data() ? text.data() : "";
  if (sqlite3_bind_text64(stmt_, index, data, text.size(), SQLITE_STATIC, SQLITE_UTF8) != SQLITE_OK)
    fail("bind");
  return *this;
}

Statement& Statement::bind_blob(int index, std::span<const std::byte> bytes) {
  // SQLITE_STATIC: tiles can be large, and the caller's buffer outlives the statement's
  // use (bindings are cleared by reset()).
  const int rc = bytes.empty()
                     ? sqlite3_bind_zeroblob(stmt_, index, 0)
                     : sqlite3_bind_blob64(stmt_, index, bytes.data(), bytes.size(), SQLITE_STATIC);
  if (rc != SQLITE_OK) fail("bind");
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  fail("step");
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

SqliteDb::SqliteDb(const std::filesystem::path& file) : file_(file) {
  const int rc =
      sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = errmsg_of(db_);
    sqlite3_close(db_);
    throw std::runtime_error("sqlite: cannot open " + file.string() + ": " + message);
  }
  sqlite3_extended_result_codes(db_, 1);
  sqlite3_busy_timeout(db_, busy_timeout_ms);
}

SqliteDb::~SqliteDb() {
  // Unfinalized statements would make close fail. The checkpointer's connection closes
  // first, so that this one, the last, checkpoints the whole WAL on close.
  statements_.clear();
  checkpointer_.reset();
  sqlite3_close(db_);
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
  char* error = nullptr;
  if (sqlite3_exec(db_, text.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = error ? error : errmsg_of(db_);
    sqlite3_free(error);
    throw std::runtime_error("sqlite: exec failed: " + message + " [" + text + "]");
  }
}

StatementUse SqliteDb::statement(std::string_view sql) {
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
Transaction::Transaction(SqliteDb& db) : db_(db) { db_.statement("SAVEPOINT tessera_tx")->step(); }

Transaction::~Transaction() {
  if (!open_) return;
  try {
    db_.exec("ROLLBACK TO tessera_tx");
    db_.exec("RELEASE tessera_tx");
  } catch (...) {
    // A destructor must not throw; SQLite rolls back an unfinished transaction on close.
  }
}

void Transaction::commit() {
  db_.statement("RELEASE tessera_tx")->step();
  open_ = false;
}

}  // namespace tessera
