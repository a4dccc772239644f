// The in-core Embree photon tracer of `portico bench pipeline`
// (incore_photon_tracer.h): load, build, then trace, each a step below.
#include "coordinator/cli/bench/incore_photon_tracer.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "common/accel/embree_accelerator.h"  // FlushDenormalsScope
#include "common/accel/embree_device.h"
#include "common/scene/store/cell_geometry.h"
#include "common/transport/photon_map.h"  // StoredPhoton: the record a deposit appends
#include "common/transport/photon_scattering.h"
#include "coordinator/cli/bench/accel_measure.h"  // Clock, secondsSince

namespace portico::cli {

namespace {

using Cells = std::vector<std::unique_ptr<CellGeometry>>;

// Every cell file mapped and validated, kept for the whole run.
Cells loadCells(const SceneStore& scene, InCorePhotonResult& result) {
  const auto loadStart = Clock::now();
  Cells cells;
  cells.reserve(scene.cells().size());
  for (const CellInfo& info : scene.cells()) {
    cells.push_back(CellGeometry::load(scene.cellPath(info.id), info.id, scene.materials().size()));
    result.triangles += cells.back()->mesh().triangleCount;
    result.bytesMapped += cells.back()->bytes();
  }
  result.cells = uint32_t(cells.size());
  result.loadSeconds = secondsSince(loadStart);
  return cells;
}

// One device, one scene over every cell; released scene first.
struct InCoreScene {
  explicit InCoreScene(const std::string& config) : device(config) {}
  ~InCoreScene() {
    if (scene) rtcReleaseScene(scene);
  }
  EmbreeDevice device;
  RTCScene scene = nullptr;
  std::vector<std::vector<float>> vertexCopies;  // cells whose positions Embree cannot read in place
};

// One triangle geometry per cell (geometry id = cell id) over the mapped
// buffers, one BVH over all of them, built on `threads` threads.
std::unique_ptr<InCoreScene> buildScene(const Cells& cells, uint32_t threads, InCorePhotonResult& result) {
  const auto buildStart = Clock::now();
  EmbreeDevice::clearErrors();
  auto embree = std::make_unique<InCoreScene>(fmt::format("threads={}", threads));
  result.deviceSeconds = secondsSince(buildStart);
  embree->scene = rtcNewScene(embree->device.handle());
  if (!embree->scene) EmbreeDevice::fail("cannot create a scene");
  rtcSetSceneFlags(embree->scene, RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(embree->scene, RTC_BUILD_QUALITY_MEDIUM);
  embree->vertexCopies.reserve(cells.size());
  for (const auto& cell : cells) {
    attachEmbreeTriangles(embree->device, embree->scene, cell->mesh(), RTC_BUILD_QUALITY_MEDIUM,
                          embree->vertexCopies.emplace_back(), cell->id());
    EmbreeDevice::check(fmt::format("cannot add cell {}", cell->id()));
  }
  rtcCommitScene(embree->scene);
  EmbreeDevice::check(fmt::format("building the scene of {} triangles failed", result.triangles));
  result.buildSeconds = secondsSince(buildStart);
  result.bvhBytes = embree->device.bytesAllocated();
  return embree;
}

// One emission batch, as the coordinator queues them (kPhotonsPerEmitBatch
// there; any size here: the photons are the same whatever the split).
struct EmitChunk {
  uint32_t light;
  uint64_t firstPath;
  uint32_t count;
  uint64_t photonsOfLight;
};

// The pass's photons in chunks of `chunkSize`, light after light, path ids
// numbered across the lights as the coordinator numbers them.
std::vector<EmitChunk> emissionChunks(const SceneStore& scene, uint64_t photons, uint32_t chunkSize) {
  const std::vector<uint64_t> shares = photonSharesOfLights(scene.lights(), photons);
  std::vector<EmitChunk> chunks;
  uint64_t nextPath = 0;
  for (uint32_t light = 0; light < shares.size(); ++light) {
    for (uint64_t first = 0; first < shares[light]; first += chunkSize)
      chunks.push_back({light, nextPath + first, uint32_t(std::min<uint64_t>(chunkSize, shares[light] - first)),
                        shares[light]});
    nextPath += shares[light];
  }
  return chunks;
}

struct ThreadCounters {
  int64_t emitted = 0, deposits = 0, absorbed = 0, escaped = 0, rays = 0;
};

// What one tracing thread reads and writes.
struct Tracer {
  const SceneStore& scene;
  const Cells& cells;
  RTCScene rtcScene;
  uint64_t seed;
  uint32_t maxBounces;
  ThreadCounters& count;
  std::vector<StoredPhoton>& stored;

  // The nearest surface along the photon's segment; false when it leaves the building.
  bool intersect(const RayState& photon, RTCIntersectContext& context, RTCRayHit& query) {
    ++count.rays;
    query.ray.org_x = photon.origin.x, query.ray.org_y = photon.origin.y, query.ray.org_z = photon.origin.z;
    query.ray.dir_x = photon.direction.x, query.ray.dir_y = photon.direction.y, query.ray.dir_z = photon.direction.z;
    query.ray.tnear = 0.0f;
    query.ray.tfar = kInfinity;
    query.ray.time = 0.0f;
    query.ray.mask = 0xffffffffu;
    query.ray.id = 0;
    query.ray.flags = 0;
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    query.hit.primID = RTC_INVALID_GEOMETRY_ID;
    query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rtcScene, &context, &query);
    return query.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }

  // CellKernel::tracePhoton, with the whole building as one cell.
  void trace(RayState photon, RTCIntersectContext& context) {
    for (;;) {
      alignas(16) RTCRayHit query;
      if (!intersect(photon, context, query)) {
        ++count.escaped;
        return;
      }
      const CellGeometry& cell = *cells[query.hit.geomID];
      const uint32_t primitive = query.hit.primID;
      const Material& material = scene.materials()[cell.material(primitive)];
      const PhotonScatter scatter =
          scatterPhoton(photon, {cell.mesh(), primitive, query.ray.tfar, query.hit.u, query.hit.v, material}, seed, maxBounces);
      if (scatter.deposited) {
        stored.push_back(scatter.deposit);
        ++count.deposits;
      }
      if (!scatter.bounced) {
        ++count.absorbed;
        return;
      }
    }
  }

  // CellKernel::emitPhotons for one chunk.
  void emit(const EmitChunk& chunk, RTCIntersectContext& context) {
    const AreaLight& light = scene.lights()[chunk.light];
    const Vec3 lightNormal = light.normal();
    const Vec3 power = light.power() / float(chunk.photonsOfLight);
    for (uint64_t path = chunk.firstPath; path < chunk.firstPath + chunk.count; ++path) {
      ++count.emitted;
      trace(emitPhoton(light, lightNormal, power, seed, path), context);
    }
  }
};

}  // namespace


InCorePhotonResult runInCorePhotonTracer(const SceneStore& scene, const InCorePhotonOptions& options) {
  if (scene.lights().empty()) throw std::invalid_argument(fmt::format("scene {} has no lights", scene.directory()));
  if (options.threads == 0) throw std::invalid_argument("the in-core tracer needs at least one thread");
  InCorePhotonResult result;
  const Cells cells = loadCells(scene, result);
  const std::unique_ptr<InCoreScene> embree = buildScene(cells, options.threads, result);

  // The photon pass: emission chunks handed out in order to the threads.
  const std::vector<EmitChunk> chunks =
      emissionChunks(scene, options.photons, std::max<uint32_t>(1, options.photonsPerChunk));
  std::atomic<size_t> nextChunk{0};
  std::vector<ThreadCounters> counters(options.threads);
  std::vector<std::vector<StoredPhoton>> deposits(options.threads);
  std::vector<std::exception_ptr> failures(options.threads);
  auto work = [&](uint32_t thread) {
    try {
      const FlushDenormalsScope flushDenormals;
      // About 2.7 deposits per photon in the generated buildings: reserve
      // more (address space only; pages are touched as records arrive).
      deposits[thread].reserve(size_t(options.photons / options.threads + 1) * 4);
      Tracer tracer{scene, cells, embree->scene, options.seed, options.maxBounces, counters[thread], deposits[thread]};
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      for (size_t c = nextChunk.fetch_add(1); c < chunks.size(); c = nextChunk.fetch_add(1))
        tracer.emit(chunks[c], context);
      EmbreeDevice::check("tracing failed");
    } catch (...) {
      failures[thread] = std::current_exception();
    }
  };

  const auto traceStart = Clock::now();
  {
    std::vector<std::thread> threads;
    for (uint32_t t = 0; t < options.threads; ++t) threads.emplace_back(work, t);
    for (std::thread& t : threads) t.join();
  }
  result.traceSeconds = secondsSince(traceStart);
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
  for (uint32_t t = 0; t < options.threads; ++t) {
    result.emitted += counters[t].emitted;
    result.deposits += counters[t].deposits;
    result.absorbed += counters[t].absorbed;
    result.escaped += counters[t].escaped;
    result.rays += counters[t].rays;
    result.depositsPerThread.push_back(int64_t(deposits[t].size()));
  }
  return result;
}

}  // namespace portico::cli
