// `embree`: Intel Embree 3's BVH over the cell's own buffers, the industry
// baseline the paper's structures are measured against.
//
// The index buffer, and the vertex buffer when the MeshView says at least
// one float past the last vertex may be read (MeshView::positionsPaddingFloats;
// Embree reads float3 vertices with 16-byte loads), are shared with Embree
// (rtcSetSharedGeometryBuffer): no copy of the mmap'd cell. Otherwise the
// vertices are copied once, with the padding; sharesVertices() tells which.
// One RTCDevice per process, made on first use.
//
// Embree uses its own triangle test: its hits are not bit-identical to those
// of portico's structures (same primitive when the nearest hit is clear,
// t within float rounding), and ties are not broken by primitive id. Use it
// to measure, or where bit-identical photons across structures do not matter.
// Tracing threads should set flush-to-zero / denormals-are-zero
// (FlushDenormalsScope), as Embree recommends.
//
// Variant: the build quality, `embree:low` (Embree's Morton builder: about
// 2.4x faster builds on the octagon's cells, rays ~0.6x as fast; the
// better choice for a cell that traces a few rays per triangle, as a photon
// pass's cells do), `embree` = `embree:medium` (binned SAH), `embree:high`
// (with spatial splits). Statistics: bytes is what the device allocated for this
// scene (net, measured around the build; approximate when several Embree
// builds run at once) plus any vertex copy; nodes, leaves and depths are not
// reported by Embree's API and stay 0.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/accel/accelerator.h"

namespace portico {

enum class EmbreeBuildQuality { Low, Medium, High };

class EmbreeAccelerator final : public Accelerator {
 public:
  // mesh's arrays must outlive this object. Throws std::runtime_error with
  // Embree's message if the device or the build fails.
  explicit EmbreeAccelerator(const MeshView& mesh, std::string_view spec = "embree",
                             EmbreeBuildQuality quality = EmbreeBuildQuality::Medium);
  ~EmbreeAccelerator() override;
  EmbreeAccelerator(const EmbreeAccelerator&) = delete;
  EmbreeAccelerator& operator=(const EmbreeAccelerator&) = delete;

  Hit intersect(const Ray& ray) const override;
  bool occluded(const Ray& ray) const override;
  Bounds3 bounds() const override { return bounds_; }
  const AcceleratorStats& stats() const override { return stats_; }

  // Whether Embree reads the MeshView's positions in place (else a copy).
  bool sharesVertices() const { return vertexCopy_.empty(); }

 private:
  void* scene_ = nullptr;  // RTCScene
  std::vector<float> vertexCopy_;
  Bounds3 bounds_;
  AcceleratorStats stats_;
};

// The configuration string of the process's Embree device (e.g. "threads=1"
// to build on one thread, for benchmarks). Takes effect only before the
// first Embree build in the process; returns false if the device exists
// already with another configuration.
bool configureEmbreeDevice(std::string_view config);

// Sets flush-to-zero and denormals-are-zero on this thread for the scope's
// lifetime, restoring the previous mode after (no-op off x86).
class FlushDenormalsScope {
 public:
  FlushDenormalsScope();
  ~FlushDenormalsScope();
  FlushDenormalsScope(const FlushDenormalsScope&) = delete;
  FlushDenormalsScope& operator=(const FlushDenormalsScope&) = delete;

 private:
  unsigned int saved_ = 0;
};

}  // namespace portico
