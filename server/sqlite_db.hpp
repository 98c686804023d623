// Thin RAII over the SQLite C API: a connection, its prepared statements (cached, so each
// SQL text is compiled once) and savepoint transactions. Every failure becomes a
// std::runtime_error naming the operation and carrying sqlite3_errmsg. Not thread-safe:
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

#include "server/wal_checkpointer.hpp"

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
  [[noreturn]] void fail(std::string_view what) const;

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
  explicit SqliteDb(const std::filesystem::path& file);
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

 private:
  static int on_wal_commit(void* self, sqlite3* db, const char* name, int pages);

  sqlite3* db_ = nullptr;
  std::filesystem::path file_;
  std::unordered_map<std::string, std::unique_ptr<Statement>> statements_;
  std::unique_ptr<WalCheckpointer> checkpointer_;
};

// A SAVEPOINT: nests, so a Store operation that is atomic on its own can also be part of
// a larger atomic change. Rolled back unless commit() is called.
class Transaction {
 public:
  explicit Transaction(SqliteDb& db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  void commit();

 private:
  SqliteDb& db_;
  bool open_ = true;
};

}  // namespace tessera
