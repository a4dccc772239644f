// The workers the coordinator has heard from: liveness, what they hold, and
// whether they are waiting for work.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <set>
#include <string>
#include <utility>

namespace portico {

struct WorkerInfo {
  std::string identity;       // ZeroMQ routing id
  std::string name;
  uint32_t cores = 1;
  uint64_t memoryBytes = 0;
  int64_t lastSeenMs = 0;
  bool idle = false;          // sent Ready and holds no lease
  std::set<uint64_t> leases;
  // Cells it recently traced, newest at the back: it likely still caches them.
  std::deque<std::pair<uint64_t, uint32_t>> recentCells;

  bool holds(uint64_t job, uint32_t cell) const {
    for (const auto& c : recentCells)
      if (c.first == job && c.second == cell) return true;
    return false;
  }
  void remember(uint64_t job, uint32_t cell, size_t capacity = 32) {
    for (auto it = recentCells.begin(); it != recentCells.end(); ++it)
      if (it->first == job && it->second == cell) {
        recentCells.erase(it);
        break;
      }
    recentCells.emplace_back(job, cell);
    while (recentCells.size() > capacity) recentCells.pop_front();
  }
};

using WorkerRegistry = std::map<std::string, WorkerInfo>;

}  // namespace portico
