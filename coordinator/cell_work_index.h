// Work per (job, phase, cell) of jobs.db's batches table, kept in memory
// and ranked: most work first (ties: the lower cell). JobStore keeps two:
// the unleased work, which the scheduler ranks for each lease (grouping
// every queued batch for each lease was a sixth of the coordinator's time),
// and all the work left, leased or not, which status shows and which tells
// a phase's end. One entry per cell with work, not per batch: memory
// bounded by the building, not the queues. The owner rebuilds it from the
// table when it cannot follow a change (a rollback, a bulk requeue).
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <tuple>

namespace portico {

class CellWorkIndex {
 public:
  struct Entry {
    int64_t work = 0;
    int64_t batches = 0;
  };

  // Adds `work` and `batches` (negative: taken away) to the cell's entry;
  // an entry left without batches goes.
  void change(uint64_t job, int phase, uint32_t cell, int64_t work, int64_t batches) {
    const auto key = std::make_tuple(job, phase, cell);
    auto it = cells_.find(key);
    if (it != cells_.end()) ranked_.erase({job, phase, -it->second.work, cell});
    else it = cells_.emplace(key, Entry{}).first;
    it->second.work += work;
    it->second.batches += batches;
    if (it->second.batches <= 0) cells_.erase(it);
    else ranked_.insert({job, phase, -it->second.work, cell});
  }
  void clear() {
    cells_.clear();
    ranked_.clear();
  }
  // Calls visit(cell, work) for the cells of (job, phase) with work, most
  // first, until it returns false.
  template <class Visit>
  void visitRanked(uint64_t job, int phase, Visit&& visit) const {
    for (auto it = ranked_.lower_bound({job, phase, std::numeric_limits<int64_t>::min(), 0}); it != ranked_.end();
         ++it) {
      const auto& [rankedJob, rankedPhase, negativeWork, cell] = *it;
      if (rankedJob != job || rankedPhase != phase) break;
      if (!visit(cell, -negativeWork)) break;
    }
  }
  bool any(uint64_t job, int phase) const {
    const auto it = ranked_.lower_bound({job, phase, std::numeric_limits<int64_t>::min(), 0});
    return it != ranked_.end() && std::get<0>(*it) == job && std::get<1>(*it) == phase;
  }
  size_t size() const { return cells_.size(); }

 private:
  std::map<std::tuple<uint64_t, int, uint32_t>, Entry> cells_;
  std::set<std::tuple<uint64_t, int, int64_t, uint32_t>> ranked_;   // (job, phase, -work, cell)
};

}  // namespace portico
