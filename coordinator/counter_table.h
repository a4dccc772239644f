// jobs.db's `counters` table (per job, name -> value), with its values in
// memory: a Result adds ~25 counters, and writing each as it came was one
// upsert per counter per Result, and every status poll read them all back.
// Here a change is made in memory and written once per outermost
// transaction (before its COMMIT: durable with the rest, never before, never
// without it), and a read costs no statement.
//
// Transactions: it follows the database's (sql::TransactionObserver). Each
// change inside one is logged with the value it replaced; a savepoint rolled
// back restores what changed since it began, a transaction rolled back
// everything, so memory always says what jobs.db says (or will say once the
// transaction commits). Outside a transaction a change is written at once.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/util/sqlite.h"

namespace portico {

class CounterTable : public sql::TransactionObserver {
 public:
  using Values = std::map<std::string, int64_t, std::less<>>;

  explicit CounterTable(sql::Database& db) : db_(db) {}

  void add(uint64_t job, std::string_view name, int64_t delta);
  // Keeps the larger of its value and `value` (a peak, not a sum).
  void raise(uint64_t job, std::string_view name, int64_t value);
  // The job's counters (none: an empty map).
  const Values& of(uint64_t job);
  // Deletes the job's counters but `keep` (a photon pass run again).
  void dropAllBut(uint64_t job, std::string_view keep);
  // A job whose counters nobody will change soon: its values leave memory
  // (read again from jobs.db when asked for). Unwritten changes stay.
  void forget(uint64_t job);

  // Transaction steps (the database it observes calls them).
  void begun(bool nested) override;
  void beforeCommit() override;   // writes what changed
  void committed(bool nested) override;
  void rolledBack(bool nested) override;

 private:
  Values& load(uint64_t job);
  void set(uint64_t job, Values& values, std::string_view name, int64_t value);
  void writeChanged();
  sql::Database& db_;
  std::unordered_map<uint64_t, Values> values_;        // the jobs read so far
  std::set<std::pair<uint64_t, std::string>, std::less<>> changed_;   // not yet written
  // What each change replaced, oldest first, and where each open savepoint's began.
  struct Undo {
    uint64_t job;
    std::string name;
    std::optional<int64_t> before;   // none: it did not exist
    bool wasChanged;
  };
  std::vector<Undo> undo_;
  std::vector<size_t> savepoints_;
};

}  // namespace portico
