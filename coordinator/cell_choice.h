// Which cell an idle worker's next lease is about: the scheduling half of
// memory coherence (docs/coordinator.md, "Which cell a lease is about").
#pragma once

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

// Load time per triangle before a worker's own is measured: a grid build
// and the cell's read (bench pipeline, octagon).
constexpr double kLoadSecondsPerTriangle = 1e-7;
// A worker's speed before its first timed lease (work per second).
constexpr double kUnmeasuredWorkPerSecond = 2e5;

}  // namespace portico
