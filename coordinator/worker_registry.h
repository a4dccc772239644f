// The workers the coordinator has heard from: liveness, what they hold, and
// whether they are waiting for work.
#pragma once

#include <algorithm>
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
  // Lease sizing: about kLeaseSeconds of this worker's measured speed.
  double workPerSecond = 0;   // rays (photons, pixel samples) per second; 0 until measured
  int64_t leaseStartedMs = 0;
  int64_t leaseWork = 0;

  static constexpr double kLeaseSeconds = 1.0;
  static constexpr int64_t kMinLeaseWork = 1000;
  // The work to put in its next lease, at most `maxWork`.
  int64_t nextLeaseWork(int64_t maxWork) const {
    if (workPerSecond <= 0) return std::min<int64_t>(maxWork, 10 * kMinLeaseWork);   // a first, short lease to measure
    return std::clamp<int64_t>(int64_t(workPerSecond * kLeaseSeconds), std::min(kMinLeaseWork, maxWork), maxWork);
  }
  // A finished lease: fold its speed into the estimate (leases under 20 ms
  // measure the round trip more than the tracing).
  void recordLease(int64_t nowMs) {
    const int64_t elapsed = nowMs - leaseStartedMs;
    if (leaseWork <= 0 || elapsed < 20) return;
    const double rate = double(leaseWork) * 1000.0 / double(elapsed);
    workPerSecond = workPerSecond <= 0 ? rate : 0.7 * workPerSecond + 0.3 * rate;
  }

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
