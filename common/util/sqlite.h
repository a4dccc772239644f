// A thin RAII layer over SQLite: a connection with a cache of prepared
// statements, statements with typed binds, and a transaction that rolls back
// in its destructor unless committed. Errors carry the database path, the
// SQL and SQLite's extended code.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>

namespace portico::sql {

// An SQLite failure, with its codes: callers tell a full or failing disk
// (SQLITE_FULL, SQLITE_IOERR: worth retrying) from everything else.
struct Error : std::runtime_error {
  Error(const std::string& what, int code, int extendedCode)
      : std::runtime_error(what), code(code), extendedCode(extendedCode) {}
  int code;           // primary result code (SQLITE_FULL, ...)
  int extendedCode;   // SQLITE_IOERR_WRITE, ...
  // The disk, not the data: full, or failing to read or write.
  bool diskTrouble() const { return code == SQLITE_FULL || code == SQLITE_IOERR; }
};

class Statement {
 public:
  Statement(sqlite3* db, sqlite3_stmt* stmt, std::string sql) : db_(db), stmt_(stmt), sql_(std::move(sql)) {}
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Binds are 1-based like SQLite's.
  Statement& bind(int index, int64_t value);
  Statement& bind(int index, double value);
  Statement& bind(int index, std::string_view text);
  Statement& bindBlob(int index, const void* data, size_t bytes);
  Statement& bindNull(int index);
  // Steps once: true while a row is available.
  bool step();
  // Steps to completion (for statements returning no rows).
  void run();
  void reset();   // resets and clears bindings, ready for reuse

  int64_t columnInt(int column) const { return sqlite3_column_int64(stmt_, column); }
  double columnDouble(int column) const { return sqlite3_column_double(stmt_, column); }
  std::string columnText(int column) const;
  std::span<const uint8_t> columnBlob(int column) const;
  bool columnIsNull(int column) const { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }

 private:
  [[noreturn]] void fail(int code, std::string_view what) const;
  sqlite3* db_;
  sqlite3_stmt* stmt_;
  std::string sql_;
};

// Told of every Transaction's steps, for a cache of what the database holds
// that writes itself back at the end of the outermost transaction
// (coordinator/counter_table.h). `nested`: a savepoint's.
class TransactionObserver {
 public:
  virtual ~TransactionObserver() = default;
  virtual void begun(bool nested) = 0;
  // The outermost transaction is about to commit: the last writes go into it.
  virtual void beforeCommit() = 0;
  virtual void committed(bool nested) = 0;
  virtual void rolledBack(bool nested) = 0;
};

class Database {
 public:
  enum class Mode { ReadOnly, ReadWriteCreate };
  // How long a statement waits for another connection's lock before failing.
  static constexpr int kBusyTimeoutMs = 5000;
  Database(const std::string& path, Mode mode);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  void exec(std::string_view sql);   // one or more statements, no results
  // A cached prepared statement, reset and ready. Valid until the database closes.
  Statement& prepare(const std::string& sql);
  int64_t lastInsertRowId() const { return sqlite3_last_insert_rowid(db_); }
  int64_t changes() const { return sqlite3_changes64(db_); }
  int userVersion();
  void setUserVersion(int version);
  const std::string& path() const { return path_; }
  sqlite3* handle() const { return db_; }
  bool inTransaction() const { return sqlite3_get_autocommit(db_) == 0; }

  // Called after any Transaction rolls back, a nested one's partial
  // rollback included (SQLite's own rollback hook sees only whole
  // transactions): for caches of what the database holds.
  void setRollbackListener(std::function<void()> listener) { rollbackListener_ = std::move(listener); }
  void notifyRollback() const {
    if (rollbackListener_) rollbackListener_();
  }
  // One observer at most (null: none); it must outlive the database or be unset.
  void setObserver(TransactionObserver* observer) { observer_ = observer; }
  TransactionObserver* observer() const { return observer_; }

 private:
  std::function<void()> rollbackListener_;
  TransactionObserver* observer_ = nullptr;
  std::string path_;
  sqlite3* db_ = nullptr;
  std::unordered_map<std::string, std::unique_ptr<Statement>> statements_;
};

// BEGIN IMMEDIATE ... COMMIT; rolls back when destroyed uncommitted.
// Inside another transaction it is a savepoint instead: commit() releases
// it into the enclosing transaction, which makes it durable (or not) with
// the rest, and destruction uncommitted undoes only what was done since it
// began.
class Transaction {
 public:
  explicit Transaction(Database& db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit();

 private:
  Database& db_;
  bool nested_ = false;
  bool done_ = false;
};

}  // namespace portico::sql
