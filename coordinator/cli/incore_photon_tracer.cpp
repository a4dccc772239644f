// The in-core Embree photon tracer of `portico bench pipeline`
// (incore_photon_tracer.h).
#include "coordinator/cli/incore_photon_tracer.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <thread>

#include "common/accel/embree_accelerator.h"  // FlushDenormalsScope
#include "common/rng.h"
#include "common/scene/cell_geometry.h"
#include "common/transport/photon_map.h"  // StoredPhoton: the record a deposit appends
#include "common/transport/sampling.h"

namespace portico::cli {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Embree reports errors through a callback; collect them and throw after the call.
struct DeviceErrors {
  std::mutex mutex;
  std::string text;
};

void onError(void* user, RTCError code, const char* message) {
  auto* errors = static_cast<DeviceErrors*>(user);
  std::lock_guard<std::mutex> lock(errors->mutex);
  if (!errors->text.empty()) errors->text += "; ";
  errors->text += fmt::format("Embree error {}{}", int(code), message ? std::string(": ") + message : "");
}

bool onMemory(void* user, ssize_t bytes, bool) {
  static_cast<std::atomic<int64_t>*>(user)->fetch_add(int64_t(bytes), std::memory_order_relaxed);
  return true;
}

// The process's devices and scenes are released in reverse order of creation.
struct EmbreeScene {
  DeviceErrors errors;
  std::atomic<int64_t> bytes{0};
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const std::string& what) {
    std::lock_guard<std::mutex> lock(errors.mutex);
    if (!errors.text.empty()) throw std::runtime_error("embree: " + what + " (" + errors.text + ")");
  }
};

// One emission batch, as the coordinator queues them (kPhotonsPerEmitBatch
// there; any size here: the photons are the same whatever the split).
struct EmitChunk {
  uint32_t light;
  uint64_t firstPath;
  uint32_t count;
  uint64_t photonsOfLight;
};

struct ThreadCounters {
  int64_t emitted = 0, deposits = 0, absorbed = 0, escaped = 0, rays = 0;
};

}  // namespace


InCorePhotonResult runInCorePhotonTracer(const SceneStore& scene, const InCorePhotonOptions& options) {
  if (scene.lights().empty()) throw std::invalid_argument(fmt::format("scene {} has no lights", scene.directory()));
  if (options.threads == 0) throw std::invalid_argument("the in-core tracer needs at least one thread");
  InCorePhotonResult result;
  const auto& materials = scene.materials();

  // Load: every cell file mapped and validated, kept for the whole run.
  const auto loadStart = Clock::now();
  std::vector<std::unique_ptr<CellGeometry>> cells;
  cells.reserve(scene.cells().size());
  for (const CellInfo& info : scene.cells()) {
    cells.push_back(CellGeometry::load(scene.cellPath(info.id), info.id, materials.size()));
    result.triangles += cells.back()->mesh().triangleCount;
    result.bytesMapped += cells.back()->bytes();
  }
  result.cells = uint32_t(cells.size());
  result.loadSeconds = secondsSince(loadStart);

  // Build: one scene, one triangle geometry per cell (geometry id = cell id)
  // over the mapped buffers, one BVH over all of them.
  const auto buildStart = Clock::now();
  EmbreeScene embree;
  const std::string config = fmt::format("threads={}", options.threads);
  embree.device = rtcNewDevice(config.c_str());
  if (!embree.device)
    throw std::runtime_error(fmt::format("embree: cannot create a device ({})", int(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(embree.device, onError, &embree.errors);
  rtcSetDeviceMemoryMonitorFunction(embree.device, onMemory, &embree.bytes);
  result.deviceSeconds = secondsSince(buildStart);
  embree.scene = rtcNewScene(embree.device);
  embree.check("cannot create a scene");
  rtcSetSceneFlags(embree.scene, RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(embree.scene, RTC_BUILD_QUALITY_MEDIUM);
  std::vector<std::vector<float>> vertexCopies;  // cells whose positions Embree cannot read in place
  for (const auto& cell : cells) {
    const MeshView& mesh = cell->mesh();
    if (mesh.triangleCount == 0 || mesh.vertexCount == 0) continue;
    RTCGeometry geometry = rtcNewGeometry(embree.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_MEDIUM);
    const float* positions = mesh.positions;
    if (mesh.positionsPaddingFloats < 1) {  // Embree reads a float past the last vertex
      vertexCopies.emplace_back(mesh.positions, mesh.positions + 3 * mesh.vertexCount);
      vertexCopies.back().push_back(0.0f);
      positions = vertexCopies.back().data();
    }
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions, 0,
                               3 * sizeof(float), mesh.vertexCount);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices, 0,
                               3 * sizeof(uint32_t), mesh.triangleCount);
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(embree.scene, geometry, cell->id());
    rtcReleaseGeometry(geometry);
    embree.check(fmt::format("cannot add cell {}", cell->id()));
  }
  rtcCommitScene(embree.scene);
  embree.check(fmt::format("building the scene of {} triangles failed", result.triangles));
  result.buildSeconds = secondsSince(buildStart);
  result.bvhBytes = embree.bytes.load();

  // The photon pass: emission chunks handed out in order to the threads.
  const std::vector<uint64_t> shares = photonSharesOfLights(scene.lights(), options.photons);
  std::vector<EmitChunk> chunks;
  uint64_t nextPath = 0;
  const uint32_t chunkSize = std::max<uint32_t>(1, options.photonsPerChunk);
  for (uint32_t light = 0; light < shares.size(); ++light) {
    for (uint64_t first = 0; first < shares[light]; first += chunkSize)
      chunks.push_back({light, nextPath + first, uint32_t(std::min<uint64_t>(chunkSize, shares[light] - first)),
                        shares[light]});
    nextPath += shares[light];
  }
  std::atomic<size_t> nextChunk{0};
  std::vector<ThreadCounters> counters(options.threads);
  std::vector<std::vector<StoredPhoton>> deposits(options.threads);
  std::vector<std::exception_ptr> failures(options.threads);
  const uint64_t seed = options.seed;
  const uint32_t maxBounces = options.maxBounces;
  RTCScene rtcScene = embree.scene;

  auto work = [&](uint32_t thread) {
    try {
      const FlushDenormalsScope flushDenormals;
      ThreadCounters& count = counters[thread];
      std::vector<StoredPhoton>& stored = deposits[thread];
      // About 2.7 deposits per photon in the generated buildings: reserve
      // more (address space only; pages are touched as records arrive).
      stored.reserve(size_t(options.photons / options.threads + 1) * 4);
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      for (size_t c = nextChunk.fetch_add(1); c < chunks.size(); c = nextChunk.fetch_add(1)) {
        const EmitChunk& chunk = chunks[c];
        const AreaLight& light = scene.lights()[chunk.light];
        const Vec3 lightNormal = light.normal();
        const Vec3 power = light.power() / float(chunk.photonsOfLight);
        for (uint64_t path = chunk.firstPath; path < chunk.firstPath + chunk.count; ++path) {
          // Emission: CellKernel::emitPhotons.
          const float u = randomUniform(seed, RandomStream::Photon, path, 0, dim::LightU);
          const float v = randomUniform(seed, RandomStream::Photon, path, 0, dim::LightV);
          Vec3 origin = offsetAlongNormal(light.pointAt(u, v), lightNormal);
          Vec3 direction =
              sampleCosineHemisphere(lightNormal, randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionU),
                                     randomUniform(seed, RandomStream::Photon, path, 0, dim::DirectionV));
          Vec3 weight = power;
          uint32_t depth = 0;
          ++count.emitted;
          // Bounces: CellKernel::tracePhoton, with the whole building as one cell.
          for (;;) {
            ++count.rays;
            alignas(16) RTCRayHit query;
            query.ray.org_x = origin.x, query.ray.org_y = origin.y, query.ray.org_z = origin.z;
            query.ray.dir_x = direction.x, query.ray.dir_y = direction.y, query.ray.dir_z = direction.z;
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
            if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
              ++count.escaped;
              break;
            }
            const CellGeometry& cell = *cells[query.hit.geomID];
            const uint32_t primitive = query.hit.primID;
            const Material& material = materials[cell.material(primitive)];
            if (material.emissive() || !(maxComponent(material.albedo) > 0)) {
              ++count.absorbed;
              break;
            }
            const Vec3 point = origin + direction * query.ray.tfar;
            Vec3 normal = normalize(cell.mesh().geometricNormal(primitive));
            if (!(dot(normal, direction) < 0)) normal = -normal;
            // As the cell kernel deposits: the lit side's normal, pointing into the surface.
            stored.push_back({point, -normal, weight, path, uint16_t(depth)});
            ++count.deposits;
            const float survival = std::min(1.0f, maxComponent(material.albedo));
            if (randomUniform(seed, RandomStream::Photon, path, depth, dim::Roulette) >= survival ||
                depth + 1u >= maxBounces) {
              ++count.absorbed;
              break;
            }
            weight = weight * material.albedo / survival;
            ++depth;
            origin = offsetAlongNormal(point, normal);
            direction =
                sampleCosineHemisphere(normal, randomUniform(seed, RandomStream::Photon, path, depth, dim::DirectionU),
                                       randomUniform(seed, RandomStream::Photon, path, depth, dim::DirectionV));
          }
        }
      }
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
  embree.check("tracing failed");
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
