// Deposit regions: workers that share the coordinator's file system write
// their photon-pass deposits into the job's photon file themselves.
//
// Why. Every deposit used to cross the coordinator: a worker copied its
// records into its Result, the socket copied them twice (out of the worker,
// into the coordinator), and the coordinator checksummed them and wrote them
// to the photon file (coordinator/append_files.h): on the octagon's pass
// (7.75 M photons, 375 MB of records) about half of the coordinator's CPU
// and, with two workers on two cores, 6 % of the pass's time
// (docs/pipeline-benchmark.md). The coordinator is one process for every
// worker; the workers are many.
//
// How. With each photon lease the coordinator sets a stretch of the job's
// photon file aside (Assign.depositRegion: path, offset, size), sized for
// the lease's work, and writes a head block there naming the job and the
// lease, with a random nonce (common/transport/deposit_region_head.h). A
// worker that can open that path and finds that head writes its deposits
// after it, every cell's records in one write, and sends where each cell's
// lie (CellPhotons.fileOffset, fileSize, fileCrc) with the nonce
// (Result.regionNonce). The coordinator records those extents as it records
// the batches it writes itself, in the Result's transaction. A worker that
// cannot (another machine, another user, a full region, a write that
// failed) sends the records in the Result as before; one Result may hold
// both.
//
// What keeps it safe.
// - Only extents inside the lease's own region, after its head, not
//   overlapping each other, of whole records, and from a Result with the
//   region's nonce are recorded (regionDeposits); anything else fails the
//   lease, naming the problem, and its work is queued again.
// - The bytes are checked against their CRC-32C when they are read, as the
//   coordinator's own batches are: damage (or a worker that wrote other
//   bytes than it said) makes the job run its photon pass again, a bounded
//   number of times (Coordinator::restartPhotonPass).
// - A region is never handed out twice, even across a coordinator restart or
//   a restarted photon pass: the end of the last region set aside is kept
//   in jobs.db (jobs.photon_region_end) in the transaction that opens the
//   lease, and the photon file always resumes past it, so a worker still
//   writing for a lost lease never writes over bytes a committed row names.
// - Regions not written to stay holes of the file: the file's disk use is
//   what was written (JobStore::jobFileBytes counts allocated blocks).
#pragma once

#include <cstdint>
#include <vector>

#include "common/transport/deposit_region_head.h"
#include "coordinator/append_files.h"
#include "proto/wire.capnp.h"

namespace portico {

// A region set aside for one lease.
struct DepositRegionGrant {
  int64_t offset = 0;   // of the head block
  int64_t size = 0;     // bytes, head block included
  deposit_region::Nonce nonce{};
};

// Bytes to set aside for a photon lease of `leaseWork` (photons and rays)
// over `cells` cells: 8 records per unit of work (the octagon's pass deposits
// ~3 per photon, portal copies included), a block per cell for the
// records' tails, and the head, in whole blocks, at most kMostRegionBytes.
// A lease that deposits more sends the rest in its Result.
constexpr int64_t kRegionBytesPerWork = 8 * 8;   // 8-byte records (photon_record.h)
constexpr int64_t kMostRegionBytes = int64_t(256) << 20;
int64_t depositRegionBytes(int64_t leaseWork, size_t cells);

// A Result's deposits in its lease's region, checked: each names a cell
// below cellCount, lies inside the region after its head, holds whole
// records (photon_record.h) and overlaps no other; and the Result carries the
// region's nonce. `grant` is null when the lease had no region. Throws
// std::runtime_error naming the lease and the problem.
struct RegionDeposit {
  uint32_t cell = 0;
  FileExtent extent;
};
std::vector<RegionDeposit> regionDeposits(uint64_t lease, const DepositRegionGrant* grant,
                                          wire::Result::Reader result, size_t cellCount);

}  // namespace portico
