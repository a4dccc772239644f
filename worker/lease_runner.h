// Runs one lease in three steps: load (lease_load.h: the cell, its
// accelerator and photon map), trace (lease_trace.h: every batch, then
// crossings into held cells) and encode (lease_result.h: the Result).
#pragma once

#include <capnp/message.h>

#include <atomic>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/transport/cell_kernel.h"
#include "proto/wire.capnp.h"
#include "worker/accelerator_choice.h"
#include "worker/cell_cache.h"

namespace portico {

// The photon table that arrived in a PhotonsReply: its batches' records, in
// order, still encoded (runLease decodes them on its cell's PhotonFrame).
std::string photonTableOf(wire::PhotonsReply::Reader reply);

// A failure in one of the lease's more cells (Assign.moreCells): the
// coordinator blames that cell, not the lease's own.
struct MoreCellError : std::runtime_error {
  MoreCellError(uint32_t cell, const std::string& what) : std::runtime_error(what), cell(cell) {}
  uint32_t cell;
};

// Throws on failure (bad cell file, bad spec); the caller reports it as a Failure.
// The scene is read from `storeDirectory` (the job's store, or the worker's
// local copy of it). Crossings into cells the cache already holds are traced
// in the lease too, up to max(forwardRays, the lease's own work) rays (0:
// none); see forwardToHeldCells in lease_trace.cpp. Throws TracingStopped
// (cell_kernel.h) soon after `stop` is set: its job was cancelled, or the
// worker is stopping; nothing is reported for such a lease. `progress` (if
// any) counts up as the lease moves: loaded, then piece by piece traced.
std::unique_ptr<capnp::MallocMessageBuilder> runLease(CellCache& cache, AcceleratorChooser& chooser,
                                                      wire::Assign::Reader assign,
                                                      std::optional<std::string> photonRecords,
                                                      const std::string& storeDirectory, int64_t forwardRays,
                                                      const std::atomic<bool>* stop = nullptr,
                                                      std::atomic<uint64_t>* progress = nullptr);

}  // namespace portico
