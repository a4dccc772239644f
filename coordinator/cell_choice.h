// Which cell an idle worker's next lease is about: the scheduling half of
// memory coherence (docs/coordinator.md, "Which cell a lease is about").
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "common/scene/store/scene_types.h"
#include "coordinator/job_store.h"
#include "coordinator/worker_registry.h"

namespace portico {

// Every cell with work is loaded by some worker sooner or later, so a cell
// nobody holds costs nothing extra whichever worker takes it, and whenever:
// ranking it below held cells deferred big cells (450 K triangles) to the
// end of a photon pass, where they ran alone. What costs is a second copy:
// a cell another worker holds is read and built again, at what a load
// costs this worker per triangle (WorkerInfo::loadSecondsPerTriangle,
// measured from its Results; kLoadSecondsPerTriangle until then), worth
// that many rays (or photons)
// at this worker's speed, and its later work is then split between two
// caches. Each candidate is valued at its pending work less that cost; the
// best value wins (on a tie, one the worker holds). A large queue is thus
// split only when it outweighs the second load, and small cells, cheap to
// load twice, are shared when a worker would otherwise wait.
//
// Except where the holder is about to be free: a queue smaller than a
// second load is left to a worker that holds the cell and whose leases in
// flight end before this worker could have loaded it (it takes the queue
// in its next lease, or in a lease's more cells). At the end of a photon
// pass, the queues are a few photons each; handing them to whichever
// worker asked first loaded a quarter of the cells a second time, at
// 5-7 ms each for 28 K triangles, for a handful of photons.
//
// `candidates`: non-empty, ranked by pending work (JobStore::pendingCells);
// only those of the first candidate's job are considered. `cells`: that
// job's scene's cells. Returns nullptr when every candidate is best left
// to its holder.
const PendingCell* chooseCell(const std::vector<PendingCell>& candidates, const std::vector<CellInfo>& cells,
                              const WorkerInfo& worker, const WorkerRegistry& workers);

// Whether candidate `c` may join `worker`'s photon lease about `chosen` as
// one of its more cells (Assign.moreCells): same job and phase, a cell this
// worker holds or that no other worker holds (taking another's would load
// it a second time), and not one that failed before (a failure in a lease
// of several cells names its cell, which then goes alone).
bool mayJoinLease(const PendingCell& c, const PendingCell& chosen, const WorkerInfo& worker,
                  const WorkerRegistry& workers, bool failedBefore);

// Cells ranked by pending work that a lease may be chosen from.
constexpr size_t kLeaseCandidates = 1024;
// What a worker's cache holds per byte of a cell's file: the geometry and
// an accelerator about twice its size (a grid; worker/cell_cache.h).
constexpr uint64_t kCachedBytesPerFileByte = 3;
inline uint64_t cachedBytesOf(const std::vector<CellInfo>& cells, uint32_t cell) {
  return cell < cells.size() ? kCachedBytesPerFileByte * cells[cell].byteCount : 0;
}
// Photon pass: a lease under this much of its worker's time takes on more
// cells, at most kMostCellsPerLease in all. A cell's emission is ~10 ms of
// a worker's time on the octagon: at 0.03 s a photon pass takes ~130
// leases instead of ~290, and the coordinator half the CPU (about half its
// photon-pass CPU is per lease: statements, commits, messages).
constexpr double kSmallLeaseSeconds = 0.03;
constexpr size_t kMostCellsPerLease = 16;

// Photon pass: a lease of `leaseWork` about `chosen`, under
// kSmallLeaseSeconds of the worker's work (a cell's emission, the end of
// the pass), takes on more cells, those it holds and those no other worker
// holds (mayJoinLease), up to that much work: one round trip and one
// Result for all of them. Their cache footprint is capped, so a worker
// whose cache forgot them (the model errs) does not pin more than a quarter
// of its budget reloading them. `take(c, maxWork)` adds up to maxWork of
// c's queue to the lease and returns the work it added (-1: none). Returns
// the lease's work with them. The coordinator's queue is jobs.db, the
// cluster model's its own (coordinator/cli/bench/cluster_model.h).
int64_t addMoreCells(const std::vector<PendingCell>& candidates, const PendingCell& chosen,
                     const std::vector<CellInfo>& cells, const WorkerInfo& worker, const WorkerRegistry& workers,
                     int64_t leaseWork, const std::function<bool(const PendingCell&)>& failedBefore,
                     const std::function<int64_t(const PendingCell&, int64_t)>& take);

// Load time per triangle before a worker's own is measured: a grid build
// and the cell's read (bench pipeline, octagon).
constexpr double kLoadSecondsPerTriangle = 1e-7;
// A worker's speed before its first timed lease (work per second).
constexpr double kUnmeasuredWorkPerSecond = 2e5;

}  // namespace portico
