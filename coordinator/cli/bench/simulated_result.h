// What a simulated worker of `portico bench coordinator` answers a lease
// with: no tracing, a Result at once, of the size and shape a traced one
// has (deposit records, crossings handed to neighbouring cells, film), and
// adding up the way the coordinator checks (coordinator/result_check.h):
// every photon or ray the lease starts ends in it or is handed on.
//
// The shape's defaults are a real render's: the 2-floor tower
// (`portico render STORE --workers 2 --photons 200000 --spp 1`) deposited
// 2.63 photons and 0.50 portal copies per photon emitted, handed 0.13 of its
// photons and 0.17 rays per camera ray on to other cells.
#pragma once

#include <capnp/message.h>

#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "common/scene/store/scene_store.h"
#include "common/transport/photon_record.h"
#include "proto/wire.capnp.h"

namespace portico::cli {

struct ResultShape {
  double depositsPerPhoton = 3.13;    // records (deposits and portal copies) per photon a lease starts
  double photonCrossings = 0.13;      // photons handed on per photon started
  double cameraCrossings = 0.17;      // render rays handed on per camera ray
  uint32_t maxDepth = 8;              // a ray that has crossed this many portals ends where it is
  double raysPerSecond = 1e6;         // the speed reported: the coordinator sizes leases by it (about 1 s)
  // Fault injection for the bench's own test: each photon Result reports
  // one photon fewer absorbed than it ended, which the coordinator refuses.
  bool miscount = false;
};

// A cell's neighbours through its portals (from the store's scene.db): where
// a simulated crossing goes. A cell without portals hands on to itself.
class CellNeighbours {
 public:
  explicit CellNeighbours(const SceneStore& scene) : CellNeighbours(scene.cells().size(), scene.portals()) {}
  CellNeighbours(size_t cellCount, const std::vector<Portal>& portals);
  uint32_t neighbour(uint32_t cell, uint64_t path) const;

 private:
  std::vector<std::vector<uint32_t>> neighbours_;
};

// Sums over a worker's Results, which the bench checks against the job's
// statistics (every photon and ray accounted for).
struct SimulatedTally {
  int64_t results = 0, emitted = 0, photonsHandedOn = 0, depositRecords = 0;
  int64_t cameraRays = 0, raysHandedOn = 0, regionRecords = 0;
  void add(const SimulatedTally& other);
};

struct SimulatedResult {
  std::unique_ptr<capnp::MallocMessageBuilder> message;   // an Envelope holding the Result
  SimulatedTally tally;
};

// The Result of `assign`. With useDepositRegion, a photon lease's deposits
// go into its deposit region when it has one, as a worker on the
// coordinator's file system writes them (worker/deposit_region_writer.h),
// and the Result names where; otherwise (or where the region cannot be
// used) the records travel in the Result, as from a worker on another machine.
SimulatedResult simulateResult(wire::Assign::Reader assign, const ResultShape& shape, const CellNeighbours& neighbours,
                               bool useDepositRegion);

}  // namespace portico::cli
