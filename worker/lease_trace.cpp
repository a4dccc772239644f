#include "worker/lease_trace.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "common/net/ray_wire.h"
#include "worker/lease_runner.h"

namespace portico {

namespace {
void traceBatches(const SceneStore& scene, CellKernel& kernel, const JobSettings& parameters, uint32_t cellId,
                  capnp::List<wire::RayBatch>::Reader batches, KernelOutputs& out) {
  for (auto batch : batches) {
    switch (batch.which()) {
      case wire::RayBatch::EMIT: {
        auto emit = batch.getEmit();
        if (!kernel.emitsHere(emit.getLight()))
          throw std::runtime_error(
              fmt::format("emission batch names light {}, which is not in cell {}", emit.getLight(), cellId));
        kernel.emitPhotons(emit.getLight(), emit.getFirstPath(), emit.getCount(), emit.getPhotonsOfLight(), out);
        break;
      }
      case wire::RayBatch::CAMERA: {
        auto camera = batch.getCamera();
        if (uint64_t(camera.getFirstPixel()) + camera.getPixelCount() > uint64_t(parameters.width) * parameters.height)
          throw std::runtime_error("camera batch lies outside the image");
        kernel.generateCameraRays(camera.getFirstPixel(), camera.getPixelCount(), out);
        break;
      }
      case wire::RayBatch::RAYS:
        for (auto ray : batch.getRays()) kernel.trace(fromWire(ray), out);
        break;
      case wire::RayBatch::SENSORS: {
        if (!parameters.analysis) throw std::runtime_error("a sensor batch in a job that is no analysis");
        std::vector<SensorTask> sensors;
        sensors.reserve(batch.getSensors().size());
        for (auto s : batch.getSensors()) {
          if (s.getIndex() >= parameters.analysis->sensors)
            throw std::runtime_error(fmt::format("sensor batch names sensor {} of {}", s.getIndex(),
                                                 parameters.analysis->sensors));
          SensorTask task{s.getIndex(), Vec3(s.getX(), s.getY(), s.getZ()), Vec3(s.getDx(), s.getDy(), s.getDz())};
          if (!isFinite(task.position) || !(std::abs(length(task.direction) - 1.0f) < 1e-3f))
            throw std::runtime_error(fmt::format("sensor {} is not a point and a unit direction", s.getIndex()));
          sensors.push_back(task);
        }
        kernel.measureSensors(sensors, out);
        break;
      }
    }
  }
  kernel.finishGathers(out);
}

int64_t workOf(capnp::List<wire::RayBatch>::Reader batches) {
  int64_t work = 0;
  for (auto batch : batches)
    work += batch.isRays() ? int64_t(batch.getRays().size()) : batch.isEmit() ? int64_t(batch.getEmit().getCount()) : 0;
  return work;
}

// The photon pass's more cells (Assign.moreCells), each in its own kernel;
// a failure names its cell.
void traceMoreCells(CellCache& cache, AcceleratorChooser& chooser, const LoadedLease& lease,
                    wire::Assign::Reader assign, const std::atomic<bool>* stop, std::atomic<uint64_t>* progress,
                    KernelOutputs& out) {
  const SceneStore& scene = *lease.scene;
  for (auto more : assign.getMoreCells()) {
    const uint32_t moreId = more.getCell();
    if (moreId >= scene.cells().size())
      throw std::runtime_error(fmt::format("lease names cell {}, which does not exist", moreId));
    try {
      LoadedCell& moreCell = loadMoreCell(cache, chooser, lease, moreId, workOf(more.getBatches()));
      CellKernel kernel(scene, *moreCell.tracer, lease.parameters, nullptr);
      kernel.setStopFlag(stop);
      kernel.setProgressCounter(progress);
      traceBatches(scene, kernel, lease.parameters, moreId, more.getBatches(), out);
    } catch (const TracingStopped&) {
      throw;
    } catch (const std::exception& e) {
      throw MoreCellError(moreId, e.what());
    } catch (const kj::Exception& e) {
      throw MoreCellError(moreId, fmt::format("malformed lease: {}", e.getDescription().cStr()));
    }
  }
}

// Crossings into cells this worker already holds (with the job's accelerator,
// and in the render phase with their photon map) are traced here, in this
// lease, instead of going back to the coordinator to come out again as a
// lease of their own. A photon bouncing between rooms the worker holds then
// finishes without a round trip per portal: the end of a photon pass is
// made of such small generations, each a lease, and the workers would sit
// idle between them. No bit changes: a ray carries its whole state, photon
// tables are sorted by content and film sums are exact. At most `limit`
// rays are forwarded (the last destination's in full), so a lease stays
// about a lease's work. Returns the rays forwarded.
int64_t forwardToHeldCells(CellCache& cache, const LoadedLease& lease, int64_t limit, KernelOutputs& out,
                           const std::atomic<bool>* stop, std::atomic<uint64_t>* progress) {
  int64_t forwarded = 0;
  for (bool forwardedSome = true; forwardedSome && forwarded < limit;) {
    forwardedSome = false;
    for (auto it = out.crossings.begin(); it != out.crossings.end() && forwarded < limit;) {
      const uint32_t destination = it->first;
      LoadedCell* held = cache.heldCell(lease.store, destination, lease.accel);
      const IndirectLight* photons = held && lease.renderPhase ? cache.indirectLight(lease.mapKey(destination)) : nullptr;
      if (!held || (lease.renderPhase && !photons)) {
        ++it;
        continue;
      }
      const std::vector<RayState> rays = std::move(it->second);
      it = out.crossings.erase(it);   // tracing may add crossings to other cells; this one stays valid
      CellKernel kernel(*lease.scene, *held->tracer, lease.parameters, photons);
      kernel.setStopFlag(stop);
      kernel.setProgressCounter(progress);
      for (const RayState& ray : rays) kernel.trace(ray, out);
      kernel.finishGathers(out);
      forwarded += int64_t(rays.size());
      forwardedSome = true;
    }
  }
  return forwarded;
}
}  // namespace

TracedLease traceLoadedLease(CellCache& cache, AcceleratorChooser& chooser, const LoadedLease& lease,
                             wire::Assign::Reader assign, int64_t forwardRays, const std::atomic<bool>* stop,
                             std::atomic<uint64_t>* progress) {
  TracedLease traced;
  // More cells come only in the photon pass (they need no photon map).
  if (assign.getMoreCells().size() > 0 && lease.renderPhase)
    throw std::runtime_error("a render lease with more cells");
  {
    CellKernel kernel(*lease.scene, *lease.cell->tracer, lease.parameters, lease.indirect);
    kernel.setStopFlag(stop);
    kernel.setProgressCounter(progress);
    traceBatches(*lease.scene, kernel, lease.parameters, assign.getCell(), assign.getBatches(), traced.out);
  }
  traceMoreCells(cache, chooser, lease, assign, stop, progress, traced.out);
  // The lease's own rays, before any are forwarded: what auto learns from.
  lease.cell->raysTraced += traced.out.counters.raySegments;
  chooser.learn(lease.renderPhase, assign.getLeaseWork(), traced.out.counters.raySegments);
  if (forwardRays > 0)
    traced.forwarded = forwardToHeldCells(cache, lease, std::max(forwardRays, assign.getLeaseWork()),
                                          traced.out, stop, progress);
  return traced;
}

}  // namespace portico
