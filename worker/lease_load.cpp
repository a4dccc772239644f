#include "worker/lease_load.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <vector>

#include "common/net/job_spec_wire.h"
#include "common/transport/photon_power_unit.h"
#include "common/transport/photon_record.h"
#include "worker/lease_runner.h"

namespace portico {

namespace {
// `--accel auto`: the cell with the structure the cost model picks for the
// rays it is expected to trace, rebuilt when a busy cell makes another pay.
LoadedCell& autoCell(CellCache& cache, AcceleratorChooser& chooser, const SceneStore& scene, uint32_t cellId,
                     int64_t cellWork, bool renderPhase) {
  const CellInfo& info = scene.cells()[cellId];
  const CellShape shape = cellShape(double(info.triangleCount), info.bounds);
  const double expected = chooser.expectedRays(renderPhase, cellWork);
  bool loadedNow = false;
  LoadedCell& cell = cache.cell(scene.directory(), cellId, "auto", [&] {
    loadedNow = true;
    const CostPrediction choice = chooser.firstChoice(shape, expected);
    spdlog::info("cell {} ({} triangles): auto chose {} for ~{:.0f} rays (predicted build {:.1f} ms, {:.0f} ns/ray)",
                 cellId, info.triangleCount, choice.candidate.spec, expected, choice.buildMs, choice.traceNsPerRay);
    return choice.candidate.spec;
  });
  if (loadedNow) return cell;
  // The rays still to come are the cell's pending work (`expected`), not
  // what it traced so far. In the photon pass a cell traces most of its
  // rays in its emission lease and then only the few photons that wander
  // back in; a bet on its past (rebuilding a busy cell for as many rays
  // again) pays for kd-trees that are never used.
  if (auto better = chooser.betterChoice(cell.builtSpec, shape, expected)) {
    spdlog::info("cell {} ({} triangles): auto rebuilds {} as {} for ~{:.0f} more rays ({} traced so far)", cellId,
                 info.triangleCount, cell.builtSpec, better->candidate.spec, expected, cell.raysTraced);
    cache.rebuildAccelerator(cell, better->candidate.spec);
  }
  return cell;
}

// A more cell's batches are a piece of its pending work, cut by the
// coordinator to fill a small lease: in the photon pass often one light's
// photons of a room that has a dozen. Chosen for that piece, the cell got a
// grid that then traced the rest of its emission piece by piece (on
// soda-hall a fifth of the photon pass's rays, at 1.5x bvh's time per ray).
// When the piece emits, the cell is taken to have every light's photons
// still to emit, each light at this one's share: an overestimate late in the
// pass costs a dearer build, an underestimate a slower structure for the
// rays the cell has left.
int64_t pendingWorkOfMoreCell(const SceneStore& scene, uint32_t cellId,
                              capnp::List<wire::RayBatch>::Reader batches) {
  uint64_t photonsOfLight = 0;
  for (auto batch : batches)
    if (batch.isEmit()) photonsOfLight = std::max(photonsOfLight, batch.getEmit().getPhotonsOfLight());
  if (photonsOfLight == 0) return 0;
  int64_t lights = 0;
  for (const AreaLight& light : scene.lights()) lights += light.cell == cellId;
  return int64_t(photonsOfLight) * std::max<int64_t>(1, lights);   // no lamps (daylight): the one emitter
}

LoadedCell& cellWithAccelerator(CellCache& cache, AcceleratorChooser& chooser, const LoadedLease& lease,
                                uint32_t cellId, int64_t work, bool renderPhase) {
  return lease.accel == "auto" ? autoCell(cache, chooser, *lease.scene, cellId, work, renderPhase)
                               : cache.cell(lease.store, cellId, lease.accel);
}

int64_t microsecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count();
}

// The cell's photon map from the records of a PhotonsReply, with its
// irradiance cache when gather hits read one. Final gathering uses every
// photon; the estimate at a camera hit only those that bounced (direct
// light is sampled with shadow rays).
std::unique_ptr<IndirectLight> assembleIndirectLight(CellCache& cache, LoadedLease& lease, uint32_t cellId,
                                                     std::string photonRecords) {
  const JobSettings& parameters = lease.parameters;
  // Room for what the assembly adds to the worker's resident memory, per
  // photon: the decoded photons and the map's copy of them in its tree's
  // order, and about 100 bytes of arrays (the canonical order's radix sort,
  // the tree's build, the index between them; photon_map.cpp,
  // point_kd_tree.cpp), with the irradiance cache's few. The heap keeps
  // each freed array's pages, so they add up: 196 bytes a photon measured
  // on a 460 K-photon map of the 5-floor tower (the records, already
  // resident, aside).
  const size_t count = photonRecords.size() / sizeof(PhotonRecord);
  constexpr size_t kAssemblyScratchPerPhoton = 100;
  cache.makeRoom(count * (2 * sizeof(StoredPhoton) + kAssemblyScratchPerPhoton));
  std::vector<StoredPhoton> photons;
  unpackRecords(photonRecords.data(), photonRecords.size(),
                PhotonFrame(lease.scene->cells()[cellId].bounds, parameters.photonRadius,
                            photonPowerUnit(*lease.scene, parameters)),
                parameters.gather > 0,
                photons);
  photonRecords.clear();
  photonRecords.shrink_to_fit();
  auto light = std::make_unique<IndirectLight>(IndirectLight{PhotonMap(std::move(photons)), std::nullopt});
  if (parameters.gather > 0 && parameters.irradiance == JobSettings::Irradiance::Precomputed) {
    const auto started = std::chrono::steady_clock::now();
    light->irradiance.emplace(light->photons, parameters.irradianceStride, parameters.irradianceK(),
                              parameters.photonRadius);
    lease.irradiancePoints = int64_t(light->irradiance->size());
    lease.irradianceMicroseconds = microsecondsSince(started);
  }
  return light;
}
}  // namespace

uint32_t photonMapBuild(const JobSettings& parameters) {
  if (parameters.gather == 0) return 0;   // bounced photons only, no irradiance cache
  if (parameters.irradiance != JobSettings::Irradiance::Precomputed) return 1;
  return 2 | (parameters.irradianceK() << 2);
}

uint64_t photonJobOf(wire::Assign::Reader assign) {
  // A coordinator always names it (protocol 9); 0 would mean the lease's own job.
  return assign.getPhotonJob() ? assign.getPhotonJob() : assign.getJob();
}

PhotonMapKey photonMapKey(wire::Assign::Reader assign) {
  return {photonJobOf(assign), assign.getCell(), photonMapBuild(jobSettingsFromWire(assign.getSpec()))};
}

LoadedLease loadLease(CellCache& cache, AcceleratorChooser& chooser, wire::Assign::Reader assign,
                      std::optional<std::string> photonRecords, const std::string& storeDirectory) {
  auto spec = assign.getSpec();
  const uint32_t cellId = assign.getCell();
  LoadedLease lease;
  lease.store = storeDirectory;
  lease.scene = &cache.scene(storeDirectory);
  // The coordinator resolved every automatic value (resolveJobSettings).
  lease.parameters = jobSettingsFromWire(spec);
  lease.photonJob = photonJobOf(assign);
  lease.renderPhase = assign.getPhase() == wire::Phase::RENDER;
  lease.accel = lease.renderPhase ? lease.parameters.renderAccel : lease.parameters.accel;
  if (lease.accel == "auto" && !lease.renderPhase)
    for (auto more : assign.getMoreCells())
      if (const int64_t pending = pendingWorkOfMoreCell(*lease.scene, more.getCell(), more.getBatches()))
        lease.morePendingWork.emplace_back(more.getCell(), pending);
  lease.cell = &cellWithAccelerator(cache, chooser, lease, cellId, assign.getCellWork(), lease.renderPhase);
  if (lease.renderPhase) {
    lease.indirect = cache.indirectLight(lease.mapKey(cellId));
    if (!lease.indirect) {
      if (!photonRecords) throw std::logic_error("render lease without photons");
      lease.indirect = &cache.storeIndirectLight(
          lease.mapKey(cellId), assembleIndirectLight(cache, lease, cellId, std::move(*photonRecords)));
    }
  }
  return lease;
}

LoadedCell& loadMoreCell(CellCache& cache, AcceleratorChooser& chooser, const LoadedLease& lease, uint32_t cellId,
                         int64_t work) {
  for (const auto& [cell, pending] : lease.morePendingWork)
    if (cell == cellId) work = std::max(work, pending);
  return cellWithAccelerator(cache, chooser, lease, cellId, work, false);
}

}  // namespace portico
