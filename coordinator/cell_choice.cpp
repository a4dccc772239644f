#include "coordinator/cell_choice.h"

#include <limits>

namespace portico {

namespace {
bool heldByAnotherWorker(const WorkerInfo& worker, const WorkerRegistry& workers, uint64_t job, uint32_t cell) {
  for (const auto& [identity, other] : workers)
    if (&other != &worker && other.holds(job, cell)) return true;
  return false;
}
}  // namespace

const PendingCell& chooseCell(const std::vector<PendingCell>& candidates, const std::vector<CellInfo>& cells,
                              const WorkerInfo& worker, const WorkerRegistry& workers) {
  const double speed = worker.workPerSecond > 0 ? worker.workPerSecond : kUnmeasuredWorkPerSecond;
  const PendingCell* chosen = &candidates.front();
  double best = -std::numeric_limits<double>::infinity();
  for (const PendingCell& c : candidates) {
    if (c.job != candidates.front().job) break;
    const bool mine = worker.holds(c.job, c.cell);
    const bool secondCopy = !mine && heldByAnotherWorker(worker, workers, c.job, c.cell);
    const double triangles = c.cell < cells.size() ? double(cells[c.cell].triangleCount) : 0.0;
    const double value = double(c.work) - (secondCopy ? triangles * kLoadSecondsPerTriangle * speed : 0.0);
    if (value > best || (value == best && mine)) {
      best = value;
      chosen = &c;
    }
  }
  return *chosen;
}

}  // namespace portico
