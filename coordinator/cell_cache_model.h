// The coordinator's model of one worker's cell cache: which cells it holds,
// so that their work goes back to it (memory coherence) and not to a worker
// that would load and build them a second time.
//
// The worker's cache (worker/cell_cache.h) keeps cells under a byte budget
// and evicts the least recently used; the model does the same with the
// bytes a cell likely takes there, so it forgets a cell about when the
// worker drops it. A worker holds every cell it can keep, often hundreds:
// a model of a fixed few dozen forgets most of them, and in a two-worker
// photon pass a fifth of the cells are then loaded and built twice.
#pragma once

#include <cstddef>
#include <cstdint>
#include <list>
#include <unordered_map>

#include "coordinator/cell_holders.h"

namespace portico {

class CellCacheModel {
 public:
  struct Held {
    uint64_t job = 0;
    uint32_t cell = 0;
    uint64_t bytes = 0;
  };
  // A worker that states no budget is taken to keep this many cells.
  static constexpr size_t kCellsWithoutBudget = 64;

  explicit CellCacheModel(uint64_t budgetBytes = 0) : budget_(budgetBytes) {}
  // A copy holds the same cells but is nobody's model in an index: it is
  // not the worker's (WorkerRegistry attaches the models it keeps).
  // Assigned to, a model stays attached and its index follows its cells.
  CellCacheModel(const CellCacheModel& other) { copyCells(other); }
  CellCacheModel& operator=(const CellCacheModel& other) {
    if (this == &other) return *this;
    CellHolders* holders = holders_;
    const WorkerInfo* owner = owner_;
    detach();
    copyCells(other);
    if (holders) attach(holders, owner);
    return *this;
  }
  ~CellCacheModel() { detach(); }

  // From now on `holders` lists `owner` for each cell this model holds.
  void attach(CellHolders* holders, const WorkerInfo* owner) {
    detach();
    holders_ = holders;
    owner_ = owner;
    for (const Held& held : order_) holders_->add(key(held.job, held.cell), owner_);
  }
  void detach() {
    if (!holders_) return;
    for (const Held& held : order_) holders_->remove(key(held.job, held.cell), owner_);
    holders_ = nullptr;
    owner_ = nullptr;
  }

  void setBudget(uint64_t budgetBytes) { budget_ = budgetBytes; }

  bool holds(uint64_t job, uint32_t cell) const { return index_.count(key(job, cell)) != 0; }

  // The cell was leased to the worker: it is now its most recently used.
  void use(uint64_t job, uint32_t cell, uint64_t bytes) {
    if (auto it = index_.find(key(job, cell)); it != index_.end()) {
      bytes_ -= it->second->bytes;
      order_.erase(it->second);
      index_.erase(it);
    } else if (holders_) {
      holders_->add(key(job, cell), owner_);
    }
    order_.push_back({job, cell, bytes});
    index_[key(job, cell)] = std::prev(order_.end());
    bytes_ += bytes;
    while (order_.size() > 1 && over()) {
      const uint64_t evicted = key(order_.front().job, order_.front().cell);
      if (holders_) holders_->remove(evicted, owner_);
      bytes_ -= order_.front().bytes;
      index_.erase(evicted);
      order_.pop_front();
    }
  }

  // Least recently used first.
  const std::list<Held>& cells() const { return order_; }
  size_t size() const { return order_.size(); }
  uint64_t bytes() const { return bytes_; }

  // What the model and CellHolders know a cell by.
  static uint64_t key(uint64_t job, uint32_t cell) { return (job << 32) ^ cell; }

 private:
  void copyCells(const CellCacheModel& other) {
    budget_ = other.budget_;
    bytes_ = other.bytes_;
    order_ = other.order_;
    index_.clear();
    for (auto it = order_.begin(); it != order_.end(); ++it) index_[key(it->job, it->cell)] = it;
  }
  bool over() const { return budget_ > 0 ? bytes_ > budget_ : order_.size() > kCellsWithoutBudget; }

  uint64_t budget_ = 0;
  uint64_t bytes_ = 0;
  CellHolders* holders_ = nullptr;   // the index that lists owner_ for this model's cells, if any
  const WorkerInfo* owner_ = nullptr;
  std::list<Held> order_;
  std::unordered_map<uint64_t, std::list<Held>::iterator> index_;
};

}  // namespace portico
