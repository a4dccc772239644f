// Embree devices and triangle geometries as portico sets them up, for the
// per-cell `embree` accelerator (embree_accelerator.h, on the process's one
// device) and for `portico bench pipeline`'s in-core tracer (a device of its
// own with its thread count, one scene over every cell).
//
// Embree reports errors on the thread whose API call failed (its calls
// catch internal exceptions, including those of build threads): a device
// collects them per thread, and check() turns them into an exception after
// the calls. It also counts the bytes it holds (its memory monitor).
#pragma once

#include <embree3/rtcore.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "common/mesh_view.h"

namespace portico {

class EmbreeDevice {
 public:
  // config: Embree's configuration string ("" for its defaults, "threads=2", ...).
  // Throws std::runtime_error when Embree cannot make the device.
  explicit EmbreeDevice(std::string config);
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice handle() const { return device_; }
  const std::string& config() const { return config_; }
  // Bytes the device holds now.
  int64_t bytesAllocated() const { return bytes_.load(std::memory_order_relaxed); }

  // Forgets the errors Embree reported on this thread so far.
  static void clearErrors();
  // Throws std::runtime_error("embree: WHAT (Embree's errors)") if Embree
  // reported errors on this thread since clearErrors().
  static void check(const std::string& what);
  [[noreturn]] static void fail(const std::string& what);

 private:
  static bool onMemory(void* user, ssize_t bytes, bool);

  std::string config_;
  RTCDevice device_ = nullptr;
  std::atomic<int64_t> bytes_{0};
};

// Adds a triangle geometry over mesh's buffers to scene, as geometry
// `geometryId` (RTC_INVALID_GEOMETRY_ID: the scene's next free id); a mesh
// without triangles adds nothing. The indices are shared with Embree, and
// the positions too when the MeshView promises a float after the last
// vertex (Embree loads each float3 vertex with a 16-byte load); else they
// are copied, with that float, into vertexCopy, which must outlive the
// scene. Throws std::runtime_error when Embree cannot make the geometry.
void attachEmbreeTriangles(const EmbreeDevice& device, RTCScene scene, const MeshView& mesh, RTCBuildQuality quality,
                           std::vector<float>& vertexCopy, unsigned geometryId = RTC_INVALID_GEOMETRY_ID);

}  // namespace portico
