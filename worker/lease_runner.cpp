#include "worker/lease_runner.h"

#include <cmath>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <deque>

#include "common/net/message.h"
#include "common/transport/photon_record.h"

namespace portico {

JobParameters parametersFromSpec(wire::JobSpec::Reader spec) {
  JobParameters p;
  p.seed = spec.getSeed();
  p.spp = spec.getSpp();
  p.width = spec.getWidth();
  p.height = spec.getHeight();
  p.lightSamples = spec.getLightSamples();
  p.photonK = spec.getPhotonK();
  p.photonRadius = spec.getPhotonRadius();
  p.gather = spec.getGather();
  p.lightHops = spec.getLightHops();
  p.aov = static_cast<JobParameters::Aov>(spec.getAov());
  p.irradiance = spec.getIrradiance() == wire::Irradiance::KNN ? JobParameters::Irradiance::Knn
                                                                : JobParameters::Irradiance::Precomputed;
  return p;
}

std::string photonTableOf(wire::PhotonsReply::Reader reply) {
  size_t size = 0;
  for (auto blob : reply.getBatches()) size += blob.size();
  std::string records;
  records.reserve(size);
  for (auto blob : reply.getBatches()) records.append(reinterpret_cast<const char*>(blob.begin()), blob.size());
  return records;
}

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
  // back in; betting on its past (rebuilding a busy cell for as many rays
  // again) paid for kd-trees that were never used.
  if (auto better = chooser.betterChoice(cell.builtSpec, shape, expected)) {
    spdlog::info("cell {} ({} triangles): auto rebuilds {} as {} for ~{:.0f} more rays ({} traced so far)", cellId,
                 info.triangleCount, cell.builtSpec, better->candidate.spec, expected, cell.raysTraced);
    cache.rebuildAccelerator(cell, better->candidate.spec);
  }
  return cell;
}

// Crossings into cells this worker already holds (with the job's accelerator,
// and in the render phase with their photon map) are traced here, in this
// lease, instead of going back to the coordinator to come out again as a
// lease of their own. A photon bouncing between rooms the worker holds then
// finishes without a round trip per portal: the end of a photon pass is
// made of such small generations, each a lease, and the workers sat idle
// between them. No bit changes: a ray carries its whole state, photon tables
// are sorted by content and film sums are exact. At most `limit` rays are
// forwarded (the last destination's in full), so a lease stays about a
// lease's work. Returns the rays forwarded.
int64_t forwardToHeldCells(CellCache& cache, const SceneStore& scene, const std::string& store,
                           const std::string& accel, uint64_t job, bool renderPhase, const JobParameters& parameters,
                           int64_t limit, KernelOutputs& out, const std::atomic<bool>* stop) {
  int64_t forwarded = 0;
  for (bool progress = true; progress && forwarded < limit;) {
    progress = false;
    for (auto it = out.crossings.begin(); it != out.crossings.end() && forwarded < limit;) {
      const uint32_t destination = it->first;
      LoadedCell* held = cache.heldCell(store, destination, accel);
      const IndirectLight* photons = held && renderPhase ? cache.indirectLight(job, destination) : nullptr;
      if (!held || (renderPhase && !photons)) {
        ++it;
        continue;
      }
      const std::vector<RayState> rays = std::move(it->second);
      it = out.crossings.erase(it);   // tracing may add crossings to other cells; this one stays valid
      CellKernel kernel(scene, *held->tracer, parameters, photons);
      kernel.setStopFlag(stop);
      for (const RayState& ray : rays) kernel.trace(ray, out);
      forwarded += int64_t(rays.size());
      progress = true;
    }
  }
  return forwarded;
}

std::unique_ptr<capnp::MallocMessageBuilder> runLease(CellCache& cache, AcceleratorChooser& chooser,
                                                      wire::Assign::Reader assign,
                                                      std::optional<std::string> photonRecords,
                                                      const std::string& storeDirectory, int64_t forwardRays,
                                                      const std::atomic<bool>* stop) {
  const auto started = std::chrono::steady_clock::now();
  auto spec = assign.getSpec();
  const std::string& store = storeDirectory;
  const uint32_t cellId = assign.getCell();
  JobParameters parameters = parametersFromSpec(spec);
  const SceneStore& scene = cache.scene(store);
  if (parameters.lightHops == kAutomaticLightHops) {
    // Lights a couple of rooms away matter; a couple of voxels away is no
    // distance at all: voxel cells sample every light.
    const auto cells = scene.meta().find("cells");
    parameters.lightHops = cells != scene.meta().end() && cells->second.rfind("grid", 0) == 0 ? -1 : 2;
  }
  const bool renderPhase = assign.getPhase() == wire::Phase::RENDER;
  // Render leases may build another structure: they trace many rays per
  // triangle, where one that costs more to build and less to trace pays.
  const std::string accel = renderPhase && spec.getRenderAccel().size() ? spec.getRenderAccel().cStr()
                            : spec.getAccel().size()                   ? spec.getAccel().cStr()
                                                                       : "grid";
  LoadedCell& cell = accel == "auto" ? autoCell(cache, chooser, scene, cellId, assign.getCellWork(), renderPhase)
                                     : cache.cell(store, cellId, accel);

  const IndirectLight* indirect = nullptr;
  int64_t irradianceMicroseconds = 0, irradiancePoints = 0;
  if (renderPhase) {
    indirect = cache.indirectLight(assign.getJob(), cellId);
    if (!indirect) {
      if (!photonRecords) throw std::logic_error("render lease without photons");
      // Final gathering uses every photon; the estimate at a camera hit only
      // those that bounced (direct light is sampled with shadow rays).
      // Room for the decoded photons, which become the map, its build's
      // scratch and the irradiance cache (under a quarter of the map).
      const size_t count = photonRecords->size() / sizeof(PhotonRecord);
      cache.makeRoom(2 * count * sizeof(StoredPhoton));
      std::vector<StoredPhoton> photons;
      unpackRecords(photonRecords->data(), photonRecords->size(),
                    PhotonFrame(scene.cells()[cellId].bounds, parameters.photonRadius), spec.getGather() > 0, photons);
      photonRecords.reset();
      auto light = std::make_unique<IndirectLight>(IndirectLight{PhotonMap(std::move(photons)), std::nullopt});
      if (parameters.gather > 0 && parameters.irradiance == JobParameters::Irradiance::Precomputed) {
        const auto precomputeStarted = std::chrono::steady_clock::now();
        light->irradiance.emplace(light->photons, parameters.irradianceStride, parameters.irradianceK(),
                                  parameters.photonRadius);
        irradiancePoints = int64_t(light->irradiance->size());
        irradianceMicroseconds = std::chrono::duration_cast<std::chrono::microseconds>(
                                     std::chrono::steady_clock::now() - precomputeStarted)
                                     .count();
      }
      indirect = &cache.storeIndirectLight(assign.getJob(), cellId, std::move(light));
    }
  }

  KernelOutputs out;
  const auto traceBatches = [&](CellKernel& kernel, uint32_t cellId, capnp::List<wire::RayBatch>::Reader batches) {
    for (auto batch : batches) {
      switch (batch.which()) {
        case wire::RayBatch::EMIT: {
          auto emit = batch.getEmit();
          if (emit.getLight() >= scene.lights().size() || scene.lights()[emit.getLight()].cell != cellId)
            throw std::runtime_error(fmt::format("emission batch names light {}, which is not in cell {}",
                                                 emit.getLight(), cellId));
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
      }
    }
  };
  // More cells come only in the photon pass (they need no photon map).
  if (assign.getMoreCells().size() > 0 && renderPhase)
    throw std::runtime_error("a render lease with more cells");
  {
    CellKernel kernel(scene, *cell.tracer, parameters, indirect);
    kernel.setStopFlag(stop);
    traceBatches(kernel, cellId, assign.getBatches());
  }
  for (auto more : assign.getMoreCells()) {
    const uint32_t moreId = more.getCell();
    if (moreId >= scene.cells().size())
      throw std::runtime_error(fmt::format("lease names cell {}, which does not exist", moreId));
    try {
      int64_t work = 0;
      for (auto batch : more.getBatches())
        work += batch.isRays() ? int64_t(batch.getRays().size()) : batch.isEmit() ? int64_t(batch.getEmit().getCount()) : 0;
      LoadedCell& moreCell = accel == "auto" ? autoCell(cache, chooser, scene, moreId, work, false)
                                             : cache.cell(store, moreId, accel);
      CellKernel kernel(scene, *moreCell.tracer, parameters, nullptr);
      kernel.setStopFlag(stop);
      traceBatches(kernel, moreId, more.getBatches());
    } catch (const TracingStopped&) {
      throw;
    } catch (const std::exception& e) {
      throw MoreCellError(moreId, e.what());
    } catch (const kj::Exception& e) {
      throw MoreCellError(moreId, fmt::format("malformed lease: {}", e.getDescription().cStr()));
    }
  }

  // The lease's own rays, before any are forwarded: what auto learns from.
  cell.raysTraced += out.counters.raySegments;
  chooser.learn(renderPhase, assign.getLeaseWork(), out.counters.raySegments);
  const int64_t forwarded =
      forwardRays > 0 ? forwardToHeldCells(cache, scene, store, accel, assign.getJob(), renderPhase, parameters,
                                           std::max(forwardRays, assign.getLeaseWork()), out, stop)
                      : 0;

  auto message = std::make_unique<capnp::MallocMessageBuilder>();
  auto result = message->initRoot<wire::Envelope>().initResult();
  result.setLease(assign.getLease());
  auto crossings = result.initCrossings(static_cast<unsigned>(out.crossings.size()));
  unsigned c = 0;
  for (const auto& [destination, rays] : out.crossings) {
    crossings[c].setCell(destination);
    auto list = crossings[c].initRays(static_cast<unsigned>(rays.size()));
    for (size_t i = 0; i < rays.size(); ++i) toWire(rays[i], list[static_cast<unsigned>(i)]);
    ++c;
  }
  auto deposits = result.initDeposits(static_cast<unsigned>(out.deposits.size()));
  unsigned cellIndex = 0;
  for (const auto& [cell, records] : out.deposits) {
    deposits[cellIndex].setCell(cell);
    deposits[cellIndex].setRecords(capnp::Data::Reader(reinterpret_cast<const kj::byte*>(records.data()),
                                                       records.size() * sizeof(PhotonRecord)));
    ++cellIndex;
  }
  auto film = result.initFilm(static_cast<unsigned>(out.film.sums().size()));
  unsigned f = 0;
  for (const auto& [pixel, rgb] : out.film.sums()) {
    film[f].setPixel(pixel);
    film[f].setR(rgb.r);
    film[f].setG(rgb.g);
    film[f].setB(rgb.b);
    ++f;
  }
  const CacheStatistics cacheStats = cache.takeStatistics();
  auto named = out.counters.named();
  named.push_back({"cells.loaded", cacheStats.cellsLoaded});
  named.push_back({"cells.cache_hits", cacheStats.cellHits});
  named.push_back({"cells.bytes_read", cacheStats.bytesRead});
  named.push_back({"photon_maps.built", cacheStats.photonMapsBuilt});
  named.push_back({"irradiance.points", irradiancePoints});
  named.push_back({"time.irradiance_us", irradianceMicroseconds});
  named.push_back({"rays.forwarded", forwarded});
  named.push_back({"leases.extra_cells", int64_t(assign.getMoreCells().size())});
  // Microseconds: most builds take well under a millisecond.
  named.push_back({"time.accel_build_us", std::llround(cacheStats.acceleratorBuildMs * 1e3)});
  // What loading a cell costs this worker: the coordinator weighs a second
  // copy of a cell by it (chooseCell).
  named.push_back({std::string_view(kLoadTimeCounter), std::llround(cacheStats.loadMs * 1e3)});
  named.push_back({std::string_view(kTrianglesLoadedCounter), cacheStats.trianglesLoaded});
  // The lease's own time here, loads included: the coordinator sizes this
  // worker's leases from it (WorkerInfo::recordLease).
  named.push_back({std::string_view(kLeaseTimeCounter),
                   std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - started)
                       .count()});
  // Which structure each cell got (auto's choices): the job's statistics
  // list them per cell and count them per spec.
  std::deque<std::string> buildNames;   // owns the names `named` views
  for (const auto& [builtCell, builtSpec] : cacheStats.builds) {
    named.push_back({buildNames.emplace_back("accel.built." + builtSpec), 1});
    named.push_back({buildNames.emplace_back(fmt::format("accel.cell.{}.{}", builtCell, builtSpec)), 1});
  }
  auto counters = result.initCounters(static_cast<unsigned>(named.size()));
  for (size_t i = 0; i < named.size(); ++i) {
    counters[static_cast<unsigned>(i)].setName(std::string(named[i].first));
    counters[static_cast<unsigned>(i)].setValue(named[i].second);
  }
  spdlog::debug("lease {} cell {}: {} batches, {} deposits, {} crossing cells, {} pixels in {:.1f} ms",
                assign.getLease(), cellId, assign.getBatches().size(), out.counters.photonDeposits,
                out.crossings.size(),
                out.film.sums().size(),
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count());
  return message;
}

}  // namespace portico
