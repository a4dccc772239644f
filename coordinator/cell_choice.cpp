#include "coordinator/cell_choice.h"

#include <limits>

namespace portico {

namespace {
double speedOf(const WorkerInfo& worker) {
  return worker.workPerSecond > 0 ? worker.workPerSecond : kUnmeasuredWorkPerSecond;
}

// Whether another worker holds the cell, and whether one of those holders
// has less than `seconds` of leased work still to trace. Only the holders
// are visited (the registry's index), so a choice costs O(candidates x
// holders), not O(candidates x workers).
struct Holders {
  bool any = false;
  bool freeWithin = false;
};
Holders holdersOf(const WorkerInfo& worker, const WorkerRegistry& workers, uint64_t job, uint32_t cell,
                  double seconds) {
  Holders holders;
  for (const WorkerInfo* other : workers.holdersOf(job, cell)) {
    if (other == &worker) continue;
    holders.any = true;
    if (!other->ready) continue;
    int64_t queued = 0;
    for (const auto& [id, lease] : other->leases) queued += lease.work;
    if (double(queued) / speedOf(*other) < seconds) holders.freeWithin = true;
  }
  return holders;
}
}  // namespace

bool mayJoinLease(const PendingCell& c, const PendingCell& chosen, const WorkerInfo& worker,
                  const WorkerRegistry& workers, bool failedBefore) {
  if (&c == &chosen || c.job != chosen.job || c.phase != chosen.phase || failedBefore) return false;
  return worker.holds(c.job, c.cell) || !holdersOf(worker, workers, c.job, c.cell, 0.0).any;
}

const PendingCell* chooseCell(const std::vector<PendingCell>& candidates, const std::vector<CellInfo>& cells,
                              const WorkerInfo& worker, const WorkerRegistry& workers) {
  const double speed = speedOf(worker);
  const double loadSecondsPerTriangle =
      worker.loadSecondsPerTriangle > 0 ? worker.loadSecondsPerTriangle : kLoadSecondsPerTriangle;
  const PendingCell* chosen = nullptr;
  double best = -std::numeric_limits<double>::infinity();
  for (const PendingCell& c : candidates) {
    if (c.job != candidates.front().job) break;
    const bool mine = worker.holds(c.job, c.cell);
    const double triangles = c.cell < cells.size() ? double(cells[c.cell].triangleCount) : 0.0;
    const double loadSeconds = triangles * loadSecondsPerTriangle;
    const Holders holders = mine ? Holders{} : holdersOf(worker, workers, c.job, c.cell, loadSeconds);
    const double value = double(c.work) - (holders.any ? loadSeconds * speed : 0.0);
    if (value < 0 && holders.freeWithin) continue;   // its holder takes it sooner
    if (value > best || (value == best && mine)) {
      best = value;
      chosen = &c;
    }
  }
  return chosen;
}

int64_t addMoreCells(const std::vector<PendingCell>& candidates, const PendingCell& chosen,
                     const std::vector<CellInfo>& cells, const WorkerInfo& worker, const WorkerRegistry& workers,
                     int64_t leaseWork, const std::function<bool(const PendingCell&)>& failedBefore,
                     const std::function<int64_t(const PendingCell&, int64_t)>& take) {
  const int64_t smallLease = int64_t(worker.workPerSecond * kSmallLeaseSeconds);
  if (chosen.phase != 0 || leaseWork >= smallLease) return leaseWork;
  uint64_t extraBytes = 0;
  size_t joined = 0;
  for (const PendingCell& c : candidates) {
    if (leaseWork >= smallLease || joined + 1 >= kMostCellsPerLease) break;
    if (!mayJoinLease(c, chosen, worker, workers, failedBefore(c))) continue;
    if (worker.memoryBytes > 0 && extraBytes + cachedBytesOf(cells, c.cell) > worker.memoryBytes / 4) continue;
    const int64_t added = take(c, smallLease - leaseWork);
    if (added < 0) continue;
    leaseWork += added;
    extraBytes += cachedBytesOf(cells, c.cell);
    ++joined;
  }
  return leaseWork;
}

}  // namespace portico
