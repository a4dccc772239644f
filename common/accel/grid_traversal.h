// The pieces `grid` and `hgrid` traverse with alike: the ray clipped to the
// grid's box, and a voxel's triangle references tested through a mailbox.
// Inline: both sit in the innermost loop of tracing.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "common/accel/triangle_intersect.h"
#include "common/mesh_view.h"
#include "common/ray.h"

namespace portico::grid_traversal {

// Clips [tEnter, tExit] to the box [low, high] (slabs). An axis the ray runs
// parallel to only decides whether the ray is inside the slab at all. False
// when nothing of the ray is left.
inline bool clipToBox(const double origin[3], const double direction[3], const double low[3], const double high[3],
                      double& tEnter, double& tExit) {
  if (!(tEnter < tExit)) return false;
  for (int axis = 0; axis < 3; ++axis) {
    if (direction[axis] == 0.0) {
      if (origin[axis] < low[axis] || origin[axis] > high[axis]) return false;
      continue;
    }
    double tNear = (low[axis] - origin[axis]) / direction[axis];
    double tFar = (high[axis] - origin[axis]) / direction[axis];
    if (tNear > tFar) std::swap(tNear, tFar);
    tEnter = std::max(tEnter, tNear);
    tExit = std::min(tExit, tFar);
  }
  return tEnter <= tExit;
}

// A direct-mapped cache of the primitives tested last, one per query (on
// the stack, so concurrent queries share nothing): a triangle spanning
// several voxels is tested once, its result does not depend on the voxel.
class Mailbox {
 public:
  Mailbox() { std::memset(slots_, 0xff, sizeof(slots_)); }   // kNoPrimitive everywhere
  // True the first time `primitive` is seen (recently); it is then recorded.
  bool firstVisit(uint32_t primitive) {
    uint32_t& slot = slots_[primitive & (kSize - 1)];
    if (slot == primitive) return false;
    slot = primitive;
    return true;
  }

 private:
  static constexpr uint32_t kSize = 64;
  uint32_t slots_[kSize];
};

// Tests the triangles references[first, end) not tested yet, folding hits
// into `best`. With AnyHit, returns true at the first hit.
template <bool AnyHit>
inline bool testReferences(const uint32_t* references, uint32_t first, uint32_t end, Mailbox& mailbox,
                           const MeshView& mesh, const WatertightRay& frame, const Ray& ray, Hit& best) {
  for (uint32_t r = first; r < end; ++r) {
    const uint32_t primitive = references[r];
    if (!mailbox.firstVisit(primitive)) continue;
    Vec3 v0, v1, v2;
    mesh.triangle(primitive, v0, v1, v2);
    float t, u, v;
    if (!intersectTriangle(frame, ray, v0, v1, v2, t, u, v)) continue;
    if constexpr (AnyHit) return true;
    if (closerThan(t, primitive, best)) best = Hit{t, primitive, u, v};
  }
  return false;
}

}  // namespace portico::grid_traversal
