#include "coordinator/counter_table.h"

#include <algorithm>

namespace portico {

CounterTable::Values& CounterTable::load(uint64_t job) {
  if (auto it = values_.find(job); it != values_.end()) return it->second;
  // What jobs.db holds is what memory would: every change is written
  // before its transaction commits, and none is written by anyone else.
  Values values;
  auto& s = db_.prepare("SELECT name, value FROM counters WHERE job = ?");
  s.bind(1, int64_t(job));
  while (s.step()) values.emplace(s.columnText(0), s.columnInt(1));
  s.reset();
  return values_.emplace(job, std::move(values)).first->second;
}

const CounterTable::Values& CounterTable::of(uint64_t job) { return load(job); }

void CounterTable::set(uint64_t job, Values& values, std::string_view name, int64_t value) {
  auto it = values.find(name);
  if (db_.inTransaction()) {
    auto key = std::make_pair(job, std::string(name));
    const bool wasChanged = changed_.count(key) != 0;
    undo_.push_back({job, key.second,
                     it == values.end() ? std::nullopt : std::optional<int64_t>(it->second), wasChanged});
    if (!wasChanged) changed_.insert(std::move(key));
  } else {
    changed_.emplace(job, std::string(name));
  }
  if (it == values.end()) values.emplace(std::string(name), value);
  else it->second = value;
  if (!db_.inTransaction()) writeChanged();
}

void CounterTable::add(uint64_t job, std::string_view name, int64_t delta) {
  Values& values = load(job);
  const auto it = values.find(name);
  set(job, values, name, (it == values.end() ? 0 : it->second) + delta);
}

void CounterTable::raise(uint64_t job, std::string_view name, int64_t value) {
  Values& values = load(job);
  const auto it = values.find(name);
  if (it != values.end() && it->second >= value) return;
  set(job, values, name, value);
}

void CounterTable::dropAllBut(uint64_t job, std::string_view keep) {
  Values& values = load(job);
  auto& s = db_.prepare("DELETE FROM counters WHERE job = ? AND name != ?");
  s.bind(1, int64_t(job)).bind(2, keep);
  s.run();
  for (auto it = values.begin(); it != values.end();) {
    if (it->first == keep) {
      ++it;
      continue;
    }
    auto key = std::make_pair(job, it->first);
    const bool wasChanged = changed_.erase(key) != 0;
    if (db_.inTransaction()) undo_.push_back({job, it->first, it->second, wasChanged});
    it = values.erase(it);
  }
}

void CounterTable::forget(uint64_t job) {
  if (db_.inTransaction()) return;   // a rollback may still restore its values
  const auto unwritten = changed_.lower_bound(std::make_pair(job, std::string()));
  if (unwritten != changed_.end() && unwritten->first == job) return;
  values_.erase(job);
}

void CounterTable::writeChanged() {
  if (changed_.empty()) return;
  auto& s = db_.prepare(
      "INSERT INTO counters(job, name, value) VALUES (?, ?, ?) "
      "ON CONFLICT(job, name) DO UPDATE SET value = excluded.value");
  for (const auto& [job, name] : changed_) {
    const Values& values = load(job);
    const auto it = values.find(name);
    if (it == values.end()) continue;   // dropped since it changed
    s.bind(1, int64_t(job)).bind(2, std::string_view(name)).bind(3, it->second);
    s.run();
  }
  // Outside a transaction each write is its own; inside one, committed()
  // forgets them once the COMMIT succeeded.
  if (!db_.inTransaction()) changed_.clear();
}

void CounterTable::begun(bool nested) {
  if (nested) savepoints_.push_back(undo_.size());
}

void CounterTable::beforeCommit() { writeChanged(); }

void CounterTable::committed(bool nested) {
  if (nested) {
    if (!savepoints_.empty()) savepoints_.pop_back();   // its changes are the enclosing transaction's now
    return;
  }
  changed_.clear();
  undo_.clear();
  savepoints_.clear();
}

void CounterTable::rolledBack(bool nested) {
  size_t from = 0;
  if (nested && !savepoints_.empty()) {
    from = savepoints_.back();
    savepoints_.pop_back();
  }
  for (size_t i = undo_.size(); i > from; --i) {
    Undo& undo = undo_[i - 1];
    Values& values = values_[undo.job];
    if (undo.before) values[undo.name] = *undo.before;
    else values.erase(undo.name);
    auto key = std::make_pair(undo.job, std::move(undo.name));
    if (undo.wasChanged) changed_.insert(std::move(key));
    else changed_.erase(key);
  }
  undo_.resize(from);
  if (!nested) {
    changed_.clear();   // every change of the transaction is undone: none is left to write
    savepoints_.clear();
  }
}

}  // namespace portico
