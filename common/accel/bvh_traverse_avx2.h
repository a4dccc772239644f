// What the two compilations of `bvh`'s traversal share (bvh_traverse_loop.h):
// the per-ray slab constants, and the entry to the AVX2 one.
#pragma once

#include <cmath>

#include "common/accel/bvh_node.h"
#include "common/accel/triangle_intersect.h"
#include "common/ray.h"

namespace portico {

// The ray as every box test needs it, per axis: t = (bound - origin') *
// inverse, origin' = origin + margin toward the near side for the near
// bounds and away from it for the far bounds, the near bound being the low
// one when the direction is positive.
// Lane 3 of each array is padding (written by four-lane stores). The AVX2
// test also takes origin' * inverse, near and far, rounded once per ray
// (set only where it is chosen).
struct BvhSlabs {
  float nearOrigin[4], farOrigin[4], inverse[4];
  float nearScaled[4], farScaled[4];
  int nearSide[3];   // 0: the low bounds are the near ones; 1: the high ones
};

// Whether 8-wide trees take the AVX2 traversal: when the processor has AVX2,
// unless useBvhAvx2(false) turned it off (tests compare both traversals).
bool bvhAvx2InUse();
// Turns the AVX2 traversal on (where the processor has it) or off, for
// every tree of the process.
void useBvhAvx2(bool use);

// The traversal of 8-wide trees with all eight boxes in one AVX2 test
// (bvh_traverse_avx2.cpp); call only when bvhAvx2InUse() and origin' *
// inverse is finite on every axis whose inverse is (it overflows only for
// directions near the smallest normal floats, which then take the SSE test).
template <bool AnyHit>
bool traverseBvh8Avx2(const BvhData<8>& tree, const Ray& ray, const BvhSlabs& slabs, const WatertightRay& frame,
                      Hit& best);

}  // namespace portico
