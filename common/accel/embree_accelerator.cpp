// Embree accelerator: one process-wide device (embree_device.h), one scene
// per cell with one triangle geometry over shared buffers, rtcIntersect1 /
// rtcOccluded1.
#include "common/accel/embree_accelerator.h"

#include <embree3/rtcore.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

#include "common/accel/embree_device.h"
#include "common/accel/triangle_intersect.h"

#if defined(__SSE__) || defined(__x86_64__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#define PORTICO_HAS_MXCSR 1
#endif

namespace portico {

namespace {

// The process's device, made on first use and kept for the process's
// lifetime (releasing it from a static destructor can race TBB's shutdown).
std::mutex deviceMutex;
std::string requestedConfig;
EmbreeDevice* processDevice = nullptr;

EmbreeDevice& sharedDevice() {
  std::lock_guard<std::mutex> lock(deviceMutex);
  if (processDevice) return *processDevice;
  processDevice = new EmbreeDevice(requestedConfig);
  spdlog::debug("embree: device ready ({}), config '{}'",
                rtcGetDeviceProperty(processDevice->handle(), RTC_DEVICE_PROPERTY_VERSION), processDevice->config());
  return *processDevice;
}

RTCScene asScene(void* scene) { return static_cast<RTCScene>(scene); }

// Whether the ray can be handed to Embree: finite, with a direction and a
// non-empty [tMin, tMax) (portico's other structures answer "no hit" too).
bool traceable(const Ray& ray) {
  return hasFiniteOriginAndDirection(ray) &&
         (ray.direction.x != 0.0f || ray.direction.y != 0.0f || ray.direction.z != 0.0f) && ray.tMin < ray.tMax;
}

// portico's hits satisfy tMin < t < tMax; Embree accepts tnear <= t <= tfar
// (a hit exactly at tnear comes back: a camera ray looking past a surface
// from t would find it again), with tnear >= 0 (a negative tMin, which
// portico's renderer never uses, is taken as 0). So both ends move one
// float inward.
void fillRay(const Ray& ray, RTCRay& out) {
  out.org_x = ray.origin.x;
  out.org_y = ray.origin.y;
  out.org_z = ray.origin.z;
  out.tnear = ray.tMin > 0.0f ? std::nextafter(ray.tMin, kInfinity) : 0.0f;
  out.dir_x = ray.direction.x;
  out.dir_y = ray.direction.y;
  out.dir_z = ray.direction.z;
  out.time = 0.0f;
  out.tfar = std::nextafter(ray.tMax, -kInfinity);
  out.mask = 0xffffffffu;
  out.id = 0;
  out.flags = 0;
}

}  // namespace

bool configureEmbreeDevice(std::string_view config) {
  std::lock_guard<std::mutex> lock(deviceMutex);
  if (processDevice) return processDevice->config() == config;
  requestedConfig = std::string(config);
  return true;
}

EmbreeAccelerator::EmbreeAccelerator(const MeshView& mesh, std::string_view spec, EmbreeBuildQuality quality) {
  const RTCBuildQuality buildQuality = quality == EmbreeBuildQuality::Low    ? RTC_BUILD_QUALITY_LOW
                                       : quality == EmbreeBuildQuality::High ? RTC_BUILD_QUALITY_HIGH
                                                                             : RTC_BUILD_QUALITY_MEDIUM;
  const auto start = std::chrono::steady_clock::now();
  stats_.spec = std::string(spec);
  if (mesh.triangleCount >= kNoPrimitive || mesh.vertexCount >= std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("embree: " + std::to_string(mesh.triangleCount) +
                                " triangles exceed the 32-bit primitive ids; split the cell");
  for (uint32_t primitive = 0; primitive < mesh.triangleCount; ++primitive) {
    const Bounds3 box = mesh.triangleBounds(primitive);
    if (isFinite(box.lo) && isFinite(box.hi)) bounds_.extend(box);
  }

  EmbreeDevice& device = sharedDevice();
  EmbreeDevice::clearErrors();
  const int64_t bytesBefore = device.bytesAllocated();
  RTCScene scene = rtcNewScene(device.handle());
  if (!scene) EmbreeDevice::fail("cannot create a scene");
  scene_ = scene;
  try {
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene, buildQuality);
    attachEmbreeTriangles(device, scene, mesh, buildQuality, vertexCopy_);
    rtcCommitScene(scene);
    EmbreeDevice::check("building the scene of " + std::to_string(mesh.triangleCount) + " triangles failed");
  } catch (...) {
    rtcReleaseScene(scene);
    scene_ = nullptr;
    throw;
  }

  const int64_t sceneBytes = device.bytesAllocated() - bytesBefore;
  stats_.triangleReferences = mesh.triangleCount;
  stats_.bytes = sizeof(*this) + uint64_t(std::max<int64_t>(sceneBytes, 0)) + vertexCopy_.capacity() * sizeof(float);
  stats_.buildMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  spdlog::debug("embree: {} triangles, vertices {}", mesh.triangleCount,
                sharesVertices() ? "shared with the cell" : "copied (no padding after the last vertex)");
}

EmbreeAccelerator::~EmbreeAccelerator() {
  if (scene_) rtcReleaseScene(asScene(scene_));
}

Hit EmbreeAccelerator::intersect(const Ray& ray) const {
  if (!traceable(ray)) return Hit{};
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  alignas(16) RTCRayHit query;
  fillRay(ray, query.ray);
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.primID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(asScene(scene_), &context, &query);
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return Hit{};
  return Hit{query.ray.tfar, query.hit.primID, query.hit.u, query.hit.v};
}

bool EmbreeAccelerator::occluded(const Ray& ray) const {
  if (!traceable(ray)) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  alignas(16) RTCRay query;
  fillRay(ray, query);
  rtcOccluded1(asScene(scene_), &context, &query);
  return query.tfar == -kInfinity;
}

// ---------------------------------------------------------------------------

FlushDenormalsScope::FlushDenormalsScope() {
#ifdef PORTICO_HAS_MXCSR
  saved_ = _mm_getcsr();
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

FlushDenormalsScope::~FlushDenormalsScope() {
#ifdef PORTICO_HAS_MXCSR
  _mm_setcsr(saved_);
#endif
}

}  // namespace portico
