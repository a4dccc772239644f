// `bvh`, `bvh:width=4`, `bvh:width=8`: a wide bounding-volume hierarchy over
// a cell's triangles. Built top-down by binned SAH on the triangles'
// centroids (Wald 2007), each node taking the Width - 1 best splits of its
// largest children (as Embree's BVH4/BVH8 builders do), into a flat array of
// nodes whose children's boxes are tested four at a time with SSE, or all
// eight at once with AVX2 where the processor has it; leaves
// of up to eight triangles (sixteen in 8-wide trees), the room's largest
// triangles (floor, ceiling, walls) in leaves of the root, copied into the 4-wide layout of the triangle
// test (the AVX2 traversal tests two such packets at once). Traversal: children nearest first, an explicit stack, any-hit for
// occluded(). The fastest of portico's structures to trace, and fast to
// build: choose it for cells that take many rays.
//
// Parameters:
//   width=W   children per node, 4 or 8 (default 8: traces faster with AVX2).
//
// Hits are identical, bit for bit, to those of `brute`: see bvh_traverse.cpp.
#pragma once

#include <memory>
#include <string_view>

#include "common/accel/accelerator.h"
#include "common/accel/bvh_node.h"

namespace portico {

struct BvhOptions {
  int width = 8;
};

// Reads width from a `bvh` spec.
BvhOptions readBvhOptions(AcceleratorParameters& parameters);

// A BVH of options.width children per node. mesh's arrays must outlive it
// only while it is being built: the leaves hold copies of the vertices.
std::unique_ptr<Accelerator> makeBvh(const MeshView& mesh, const BvhOptions& options, std::string_view spec);

template <int Width>
class WideBvh final : public Accelerator {
 public:
  explicit WideBvh(const MeshView& mesh, std::string_view spec);

  Hit intersect(const Ray& ray) const override;
  bool occluded(const Ray& ray) const override;
  Bounds3 bounds() const override { return tree_.bounds; }
  const AcceleratorStats& stats() const override { return stats_; }

  // The flat tree (for tests and statistics).
  const BvhData<Width>& data() const { return tree_; }

 private:
  template <bool AnyHit>
  bool traverse(const Ray& ray, Hit& best) const;
  template <bool AnyHit>
  bool testEveryPacket(const Ray& ray, Hit& best) const;

  BvhData<Width> tree_;
  AcceleratorStats stats_;
};

}  // namespace portico
