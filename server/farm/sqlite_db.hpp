// Thin RAII over the SQLite C API: a connection, its prepared statements (cached, so each
// SQL text is compiled once) and savepoint transactions. Every failure becomes a
// StoreError naming the operation, carrying sqlite3_errmsg and, for a failed file
// operation, what the system said (a full disk is "the disk is full"). Not thread-safe:
// the owner serializes access.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "server/farm/wal_checkpointer.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace tessera {

class Statement {
 public:
  Statement(sqlite3* db, std::string_view sql);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Parameters are 1-based, as in SQLite.
  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, static_cast<std::int64_t>(value)); }
  Statement& bind(int index, std::string_view text);
  // As bind(), without SQLite's copy of the text, which must outlive the statement's use:
  // for a scene's text of tens of megabytes.
  Statement& bind_view(int index, std::string_view text);
  Statement& bind_blob(int index, std::span<const std::byte> bytes);

  // True while there is a row to read; false once done.
  bool step();
  // For statements that return no rows.
  void run();

  // Columns are 0-based, as in SQLite. NULL reads as 0, "" or an empty span.
  std::int64_t column_int64(int index) const;
  int column_int(int index) const { return static_cast<int>(column_int64(index)); }
  std::string column_text(int index) const;
  // Valid until the next step() or reset().
  std::span<const std::byte> column_blob(int index) const;

  // Ends the current use: releases the read snapshot and clears bindings.
  void reset();

 private:
  [[noreturn]] void fail(std::string_view what, int rc) const;

  sqlite3_stmt* stmt_ = nullptr;
  std::string sql_;
};

// A cached statement in use; resets it when the use ends, so that no statement keeps a
// read transaction open (which would hold back WAL checkpoints).
class StatementUse {
 public:
  explicit StatementUse(Statement& statement) : statement_(&statement) {}
  ~StatementUse() { statement_->reset(); }
  StatementUse(const StatementUse&) = delete;
  StatementUse& operator=(const StatementUse&) = delete;

  Statement* operator->() const { return statement_; }
  Statement& operator*() const { return *statement_; }

 private:
  Statement* statement_;
};

class SqliteDb {
 public:
  // `setup` (pragmas) runs on every connection opened to `file`: this one, and any that
  // reopen() makes.
  explicit SqliteDb(const std::filesystem::path& file, std::vector<std::string> setup = {});
  ~SqliteDb();
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;

  // Runs SQL text without parameters (schema, pragmas, savepoints); rows are discarded.
  void exec(std::string_view sql);
  // Prepared once per SQL text, then reused.
  StatementUse statement(std::string_view sql);

  // The first column of the first row as text ("" when there is no row), uncached: for
  // pragmas.
  std::string query_text(std::string_view sql);

  // For a database in WAL mode: from now on its checkpoints run on a thread of their own
  // (see WalCheckpointer), not inside a commit. Should that thread fall far behind, a
  // commit checkpoints as SQLite would, so that the WAL cannot grow without bound.
  void checkpoint_in_background();

  // Whether SQLite holds a transaction open on this connection (it is not in autocommit).
  // Outside a Transaction it never does: a failure that could leave one open ends it.
  bool in_transaction() const;
  // Closes the connection and opens it again, running `setup` again: what is left when
  // even ROLLBACK does not end a transaction. Whatever that transaction held is gone.
  void reopen();

 private:
  friend class Transaction;
  static int on_wal_commit(void* self, sqlite3* db, const char* name, int pages);
  void open();
  void close();
  // Ends whatever transaction SQLite still holds, after the outermost Transaction failed
  // or was abandoned: ROLLBACK (which in WAL mode writes nothing, so a full disk cannot
  // refuse it), or reopen() should even that leave it open.
  void end_transaction() noexcept;

  sqlite3* db_ = nullptr;
  std::filesystem::path file_;
  std::vector<std::string> setup_;
  int depth_ = 0;  // Transactions open on it
  std::unordered_map<std::string, std::unique_ptr<Statement>> statements_;
  std::unique_ptr<WalCheckpointer> checkpointer_;
};

// A SAVEPOINT: nests, so a Store operation that is atomic on its own can also be part of
// a larger atomic change. Rolled back unless commit() is called.
//
// The outermost one is the transaction SQLite commits. After it ends, however it ends, the
// connection is back in autocommit, checked: should its commit fail (a full disk refuses
// the RELEASE), it is rolled back whole; should SQLite roll it back on its own (it may,
// on SQLITE_FULL or an I/O error), every later statement of it fails rather than
// committing alone.
class Transaction {
 public:
  explicit Transaction(SqliteDb& db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  void commit();

 private:
  SqliteDb& db_;
  bool outermost_;
  bool open_ = true;
};

}  // namespace tessera
