// Which workers' cache models hold each cell: the coordinator asks it for
// every candidate of every lease (cell_choice.h), and walking every
// worker's model instead cost O(candidates x workers) per lease, most of
// the coordinator's time from a few dozen workers on.
#pragma once

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace portico {

struct WorkerInfo;

// Kept by the models themselves (CellCacheModel::attach): a cell enters a
// worker's list when its model takes it in and leaves when it evicts it or
// the model goes. The order of a list is no order at all.
class CellHolders {
 public:
  using Workers = std::vector<const WorkerInfo*>;

  void add(uint64_t key, const WorkerInfo* worker) { holders_[key].push_back(worker); }
  void remove(uint64_t key, const WorkerInfo* worker) {
    const auto it = holders_.find(key);
    if (it == holders_.end()) return;
    Workers& workers = it->second;
    const auto held = std::find(workers.begin(), workers.end(), worker);
    if (held == workers.end()) return;
    *held = workers.back();
    workers.pop_back();
    if (workers.empty()) holders_.erase(it);
  }
  // `key`: CellCacheModel::key(job, cell).
  const Workers& of(uint64_t key) const {
    static const Workers kNobody;
    const auto it = holders_.find(key);
    return it == holders_.end() ? kNobody : it->second;
  }
  size_t cellsHeld() const { return holders_.size(); }

 private:
  std::unordered_map<uint64_t, Workers> holders_;
};

}  // namespace portico
