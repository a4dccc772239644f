// The Assign message of a lease (the broker's reply to a worker's request
// for work): what the scheduler chose and the store leased, written into
// the message; and what its Result must add up to (result_check.h), summed
// as its batches are copied. No statement, no file: the caller read the
// batches (JobStore::openLease, addToLease) and set the deposit region aside.
#pragma once

#include <capnp/message.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "coordinator/job_store.h"
#include "coordinator/result_check.h"
#include "proto/wire.capnp.h"

namespace portico {

struct AssignContents {
  LeaseRecord lease;                  // id, job, cell, phase, attempt
  wire::JobSpec::Reader spec;         // the job's, as resolved
  uint64_t photonJob = 0;             // whose photon tables a render lease reads
  uint32_t renderPass = 0;            // a render lease's pass (its seed: passSeed)
  int64_t cellWork = 0;               // the cell's pending work when it was chosen
  // A photon lease's deposit region: the job's photon file, where it starts
  // and its size (coordinator/deposit_regions.h). None: no region.
  struct Region {
    std::string path;
    int64_t offset = 0, size = 0;
  };
  std::optional<Region> region;
  const std::vector<QueuedBatch>* batches = nullptr;                                      // its own cell's
  const std::vector<std::pair<uint32_t, std::vector<QueuedBatch>>>* moreCells = nullptr;   // photon pass
};

// The lease's work: its batches' and its more cells'.
int64_t leaseWorkOf(const AssignContents& contents);

// Writes the Assign into `message` (its root: an Envelope) and returns what
// its Result must add up to.
LeaseExpectation encodeAssign(const AssignContents& contents, capnp::MallocMessageBuilder& message);

}  // namespace portico
