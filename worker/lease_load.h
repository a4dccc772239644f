// A lease's first step: what it traces with. The scene, the job's
// parameters, the lease's cell with the job's accelerator, and in the
// render phase the cell's photon map, assembled from the photons that came
// with the lease when the cache does not hold it yet.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/transport/cell_kernel.h"
#include "proto/wire.capnp.h"
#include "worker/accelerator_choice.h"
#include "worker/cell_cache.h"

namespace portico {

// How a cell's photon map is built from its photon table, as a number: which
// photons it keeps (all for final gathering, else those that bounced), and
// whether it precomputes irradiance, with which k. Part of PhotonMapKey.
uint32_t photonMapBuild(const JobSettings& parameters);
// The job whose photon tables a lease of `assign` reads (Assign.photonJob).
uint64_t photonJobOf(wire::Assign::Reader assign);
// The photon map a render lease of `assign` reads for its own cell
// (LoadedLease::mapKey: for any cell it traces).
PhotonMapKey photonMapKey(wire::Assign::Reader assign);

struct LoadedLease {
  const SceneStore* scene = nullptr;
  std::string store;               // the store directory the scene was read from
  JobSettings parameters;
  uint64_t photonJob = 0;          // whose photon tables its maps come from (Assign.photonJob)
  std::string accel;               // the structure this lease's cells are traced with
  bool renderPhase = false;
  LoadedCell* cell = nullptr;      // the lease's own cell
  const IndirectLight* indirect = nullptr;   // its photon map (render phase)
  int64_t irradiancePoints = 0;    // precomputed by this lease
  int64_t irradianceMicroseconds = 0;
  // `--accel auto`, photon pass: the pending work each more cell is expected
  // to have, beyond the piece the lease holds (pendingWorkOfMoreCell).
  std::vector<std::pair<uint32_t, int64_t>> morePendingWork;
  PhotonMapKey mapKey(uint32_t cell) const { return {photonJob, cell, photonMapBuild(parameters)}; }
};

LoadedLease loadLease(CellCache& cache, AcceleratorChooser& chooser, wire::Assign::Reader assign,
                      std::optional<std::string> photonRecords, const std::string& storeDirectory);

// Another cell of the lease (Assign.moreCells) with the lease's structure;
// `work`: the rays it is to trace, for `--accel auto`.
LoadedCell& loadMoreCell(CellCache& cache, AcceleratorChooser& chooser, const LoadedLease& lease, uint32_t cellId,
                         int64_t work);

}  // namespace portico
