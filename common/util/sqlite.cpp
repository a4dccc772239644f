#include "common/util/sqlite.h"

#include <fmt/format.h>

#include <cstring>
#include <stdexcept>

namespace portico::sql {

namespace {
// What the operating system said, when SQLite's error came from a system
// call ("unable to open database file" alone does not say why). Other
// errors leave an older, unrelated errno behind: not shown.
std::string systemCause(sqlite3* db, int code) {
  const int primary = code & 0xff;
  if (primary != SQLITE_CANTOPEN && primary != SQLITE_IOERR && primary != SQLITE_FULL && primary != SQLITE_READONLY)
    return {};
  const int error = db ? sqlite3_system_errno(db) : 0;
  return error ? fmt::format(" ({})", std::strerror(error)) : std::string();
}

[[noreturn]] void throwError(sqlite3* db, int code, std::string_view context) {
  const int extended = db ? sqlite3_extended_errcode(db) : code;
  throw Error(fmt::format("sqlite: {}: {}{} (code {}, extended {})", context,
                          db ? sqlite3_errmsg(db) : sqlite3_errstr(code), systemCause(db, code), code, extended),
              code & 0xff, extended);
}
}  // namespace

Statement::~Statement() { sqlite3_finalize(stmt_); }

void Statement::fail(int code, std::string_view what) const {
  const char* file = sqlite3_db_filename(db_, "main");
  throwError(db_, code, fmt::format("{} '{}' in {}", what, sql_, file ? file : "?"));
}

Statement& Statement::bind(int index, int64_t value) {
  if (int rc = sqlite3_bind_int64(stmt_, index, value); rc != SQLITE_OK) fail(rc, "bind");
  return *this;
}
Statement& Statement::bind(int index, double value) {
  if (int rc = sqlite3_bind_double(stmt_, index, value); rc != SQLITE_OK) fail(rc, "bind");
  return *this;
}
Statement& Statement::bind(int index, std::string_view text) {
  if (int rc = sqlite3_bind_text64(stmt_, index, text.data(), text.size(), SQLITE_TRANSIENT, SQLITE_UTF8);
      rc != SQLITE_OK)
    fail(rc, "bind");
  return *this;
}
Statement& Statement::bindBlob(int index, const void* data, size_t bytes) {
  if (int rc = sqlite3_bind_blob64(stmt_, index, bytes ? data : "", bytes, SQLITE_TRANSIENT); rc != SQLITE_OK)
    fail(rc, "bind");
  return *this;
}
Statement& Statement::bindNull(int index) {
  if (int rc = sqlite3_bind_null(stmt_, index); rc != SQLITE_OK) fail(rc, "bind");
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  fail(rc, "step");
}

void Statement::run() {
  while (step()) {
  }
  reset();
}

void Statement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

std::string Statement::columnText(int column) const {
  const unsigned char* text = sqlite3_column_text(stmt_, column);
  return text ? std::string(reinterpret_cast<const char*>(text), sqlite3_column_bytes(stmt_, column))
              : std::string();
}

std::span<const uint8_t> Statement::columnBlob(int column) const {
  const void* data = sqlite3_column_blob(stmt_, column);
  const int bytes = sqlite3_column_bytes(stmt_, column);
  return {static_cast<const uint8_t*>(data), static_cast<size_t>(bytes)};
}

Database::Database(const std::string& path, Mode mode) : path_(path) {
  const int flags = mode == Mode::ReadOnly ? SQLITE_OPEN_READONLY
                                           : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  const int rc = sqlite3_open_v2(path.c_str(), &db_, flags | SQLITE_OPEN_NOMUTEX, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = (db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc)) + systemCause(db_, rc);
    const int extended = db_ ? sqlite3_extended_errcode(db_) : rc;
    sqlite3_close(db_);
    db_ = nullptr;
    throw Error(fmt::format("sqlite: cannot open {}: {}", path, message), rc & 0xff, extended);
  }
  sqlite3_extended_result_codes(db_, 1);
  sqlite3_busy_timeout(db_, kBusyTimeoutMs);
}

Database::~Database() {
  statements_.clear();
  sqlite3_close(db_);
}

void Database::exec(std::string_view sql) {
  char* error = nullptr;
  const std::string text(sql);
  const int rc = sqlite3_exec(db_, text.c_str(), nullptr, nullptr, &error);
  if (rc != SQLITE_OK) {
    std::string message = (error ? error : sqlite3_errstr(rc)) + systemCause(db_, rc);
    sqlite3_free(error);
    const int extended = sqlite3_extended_errcode(db_);
    throw Error(fmt::format("sqlite: {} in {}: {} (extended code {})", text.substr(0, 80), path_, message, extended),
                rc & 0xff, extended);
  }
}

Statement& Database::prepare(const std::string& sql) {
  auto it = statements_.find(sql);
  if (it != statements_.end()) {
    it->second->reset();
    return *it->second;
  }
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v3(db_, sql.c_str(), static_cast<int>(sql.size()), SQLITE_PREPARE_PERSISTENT,
                                    &stmt, nullptr);
  if (rc != SQLITE_OK) throwError(db_, rc, fmt::format("prepare '{}' in {}", sql, path_));
  auto [inserted, _] = statements_.emplace(sql, std::make_unique<Statement>(db_, stmt, sql));
  return *inserted->second;
}

int Database::userVersion() {
  Statement& s = prepare("PRAGMA user_version");
  s.step();
  const int version = static_cast<int>(s.columnInt(0));
  s.reset();
  return version;
}

void Database::setUserVersion(int version) { exec(fmt::format("PRAGMA user_version = {}", version)); }

// Begin and commit run as prepared statements: the coordinator opens a few
// (nested) transactions per Result, and parsing their SQL each time costs ~3 %
// of its CPU in a photon pass.
Transaction::Transaction(Database& db) : db_(db), nested_(db.inTransaction()) {
  db_.prepare(nested_ ? "SAVEPOINT nested" : "BEGIN IMMEDIATE").run();
  if (auto* observer = db_.observer()) observer->begun(nested_);
}

Transaction::~Transaction() {
  if (!done_) {
    try {
      // Savepoints of the same name nest: these reach the innermost, ours.
      db_.exec(nested_ ? "ROLLBACK TO nested; RELEASE nested" : "ROLLBACK");
    } catch (...) {
      // Destructors must not throw; the connection reports the next error.
    }
    db_.notifyRollback();
    if (auto* observer = db_.observer()) observer->rolledBack(nested_);
  }
}

void Transaction::commit() {
  auto* observer = db_.observer();
  if (observer && !nested_) observer->beforeCommit();
  db_.prepare(nested_ ? "RELEASE nested" : "COMMIT").run();
  done_ = true;
  if (observer) observer->committed(nested_);
}

}  // namespace portico::sql
