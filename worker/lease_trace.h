// A lease's second step: trace its batches in its cell and its more cells,
// then the crossings into cells this worker already holds.
#pragma once

#include <atomic>
#include <cstdint>

#include "common/transport/cell_kernel.h"
#include "proto/wire.capnp.h"
#include "worker/accelerator_choice.h"
#include "worker/cell_cache.h"
#include "worker/lease_load.h"

namespace portico {

struct TracedLease {
  KernelOutputs out;
  int64_t forwarded = 0;   // rays traced in held neighbour cells (forwardToHeldCells)
};

// Throws MoreCellError (lease_runner.h) naming a more cell that failed, and
// TracingStopped soon after `stop` is set. `progress` (if any) counts up as
// the tracing moves (CellKernel::setProgressCounter).
TracedLease traceLoadedLease(CellCache& cache, AcceleratorChooser& chooser, const LoadedLease& lease,
                             wire::Assign::Reader assign, int64_t forwardRays, const std::atomic<bool>* stop,
                             std::atomic<uint64_t>* progress = nullptr);

}  // namespace portico
