// Embree devices and triangle geometries (embree_device.h).
#include "common/accel/embree_device.h"

#include <stdexcept>
#include <utility>

namespace portico {

namespace {

thread_local std::string embreeErrors;

void onEmbreeError(void*, RTCError code, const char* message) {
  if (!embreeErrors.empty()) embreeErrors += "; ";
  embreeErrors += "Embree error " + std::to_string(int(code)) + (message ? std::string(": ") + message : "");
}

}  // namespace

EmbreeDevice::EmbreeDevice(std::string config) : config_(std::move(config)) {
  device_ = rtcNewDevice(config_.empty() ? nullptr : config_.c_str());
  if (!device_)
    throw std::runtime_error("embree: cannot create the device (error " +
                             std::to_string(int(rtcGetDeviceError(nullptr))) + "; config '" + config_ + "')");
  rtcSetDeviceErrorFunction(device_, onEmbreeError, nullptr);
  rtcSetDeviceMemoryMonitorFunction(device_, onMemory, this);
}

EmbreeDevice::~EmbreeDevice() { rtcReleaseDevice(device_); }

bool EmbreeDevice::onMemory(void* user, ssize_t bytes, bool) {
  static_cast<EmbreeDevice*>(user)->bytes_.fetch_add(int64_t(bytes), std::memory_order_relaxed);
  return true;
}

void EmbreeDevice::clearErrors() { embreeErrors.clear(); }

void EmbreeDevice::check(const std::string& what) {
  if (!embreeErrors.empty()) fail(what);
}

void EmbreeDevice::fail(const std::string& what) {
  std::string errors;
  errors.swap(embreeErrors);
  throw std::runtime_error("embree: " + what + (errors.empty() ? "" : " (" + errors + ")"));
}

void attachEmbreeTriangles(const EmbreeDevice& device, RTCScene scene, const MeshView& mesh, RTCBuildQuality quality,
                           std::vector<float>& vertexCopy, unsigned geometryId) {
  if (mesh.triangleCount == 0 || mesh.vertexCount == 0) return;
  RTCGeometry geometry = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
  if (!geometry) EmbreeDevice::fail("cannot create a triangle geometry");
  rtcSetGeometryBuildQuality(geometry, quality);
  const float* positions = mesh.positions;
  if (mesh.positionsPaddingFloats < 1) {
    vertexCopy.reserve(3 * mesh.vertexCount + 1);
    vertexCopy.assign(mesh.positions, mesh.positions + 3 * mesh.vertexCount);
    vertexCopy.push_back(0.0f);
    positions = vertexCopy.data();
  }
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions, 0, 3 * sizeof(float),
                             mesh.vertexCount);
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices, 0,
                             3 * sizeof(uint32_t), mesh.triangleCount);
  rtcCommitGeometry(geometry);
  if (geometryId == RTC_INVALID_GEOMETRY_ID)
    rtcAttachGeometry(scene, geometry);
  else
    rtcAttachGeometryByID(scene, geometry, geometryId);
  rtcReleaseGeometry(geometry);
}

}  // namespace portico
