// A Result's work written into jobs.db and the files beside it (the
// broker's "worker replied" step): its crossings queued as batches of the
// cells they enter, its deposits recorded in the cells' photon tables
// (those the worker wrote into its lease's deposit region by their place
// alone), its film summed. In the caller's transaction: anything thrown
// leaves nothing of it once that rolls back. The Result's counts were
// checked against its lease before (result_check.h); its counters, the
// lease's closing and what comes next are the coordinator's.
#pragma once

#include <cstdint>

#include "coordinator/deposit_regions.h"
#include "coordinator/job_store.h"
#include "proto/wire.capnp.h"

namespace portico {

struct ResultTarget {
  uint64_t lease = 0;
  uint64_t job = 0;
  int phase = 0;
  size_t cellCount = 0;        // cells of the job's store: a Result names no other
  uint64_t pixelCount = 0;     // of its image (film)
};

// Throws BadResultError (a cell that does not exist, a photon table of no
// whole records, a deposit region misused) or FilmRangeError (a film sum
// beyond the film's range).
void applyResult(JobStore& store, const ResultTarget& target, const DepositRegionGrant* region,
                 wire::Result::Reader result);

}  // namespace portico
