// A test hook, not a feature: PORTICO_TEST_FAULT, read by the worker alone,
// makes it send the bad Results the coordinator must refuse
// (coordinator/result_check.h), so that the integration tests check that
// refusal with real worker processes instead of hand-forged messages.
//   zero-deposits   every deposit record zeroed (their CRCs still right) and
//                   the photon counters zero: a worker that traced nothing
//   drop-crossings  rays handed on to other cells left out, counters honest
//   negative-film   every film value negated
//   duplicate-crossings  a render lease's rays handed on sent twice
//   drop-render-crossings  a render lease's rays handed on left out, its
//                   counters honest: rays lost between cells
//   uncounted-rays  a render lease's emission, shadow, gather and finished
//                   ray counters zeroed: a worker that says it traced none
//   hang-in-lease   the first lease blocks for good before its cell is read,
//                   as in a read that never returns (a hung file system):
//                   its tracing thread stuck, its heartbeats going on
//   stall-in-lease  the same for 4 s, after which the lease goes on
//   busy-in-lease   the first lease's tracing thread computes for 4 s
//                   without counting progress, as a long accelerator or
//                   photon map build does: its CPU time is its progress
// Unset (always, outside tests): nothing changes.
#pragma once

#include "common/transport/cell_kernel.h"
#include "proto/wire.capnp.h"

namespace portico {

// Before the Result is encoded (deposits, crossings, counters).
void applyTestFault(KernelOutputs& out, bool renderLease);
// After (film values).
void applyTestFault(wire::Result::Builder result);
// As a lease starts, on the tracing thread (hang-, stall-, busy-in-lease).
void stallIfTestFault();

}  // namespace portico
