// A lease's last step: its outputs and counters as a Result message.
#pragma once

#include <capnp/message.h>

#include <chrono>
#include <cstdint>
#include <memory>

#include "common/transport/cell_kernel.h"
#include "common/util/process_memory.h"
#include "proto/wire.capnp.h"
#include "worker/cell_cache.h"

namespace portico {

// What the lease measured beside the kernel's counters.
struct LeaseFigures {
  CacheStatistics cache;
  int64_t irradiancePoints = 0;
  int64_t irradianceMicroseconds = 0;
  int64_t forwarded = 0;
  int64_t moreCells = 0;
  // When the lease began here: its own time, loads and encoding included,
  // is counted as its counters are encoded.
  std::chrono::steady_clock::time_point started;
  ThreadTimes startedTimes;   // the tracing thread's, then
};

// The deposits of a photon lease with a deposit region go into the job's
// photon file where this worker can write it (worker/deposit_region_writer.h),
// the rest, and every other lease's, into the Result.
std::unique_ptr<capnp::MallocMessageBuilder> encodeResult(wire::Assign::Reader assign, const KernelOutputs& out,
                                                          const LeaseFigures& figures);

}  // namespace portico
