// `bvh`'s traversal of 8-wide trees, compiled for AVX2 and FMA: the eight
// children's boxes in one test. Chosen at run time (bvhAvx2InUse), so the
// program still runs on any x86-64. Every header is included before the
// target pragma, so the inline functions they define stay baseline code;
// only the loop (bvh_traverse_loop.h, internal linkage) and the box test
// below are compiled for AVX2. The box test takes each slab's distance in
// one fused multiply-add, t = bound * inverse - origin' * inverse, with
// origin' * inverse rounded once per ray: its rounding is at most one ulp of
// origin' in distance, inside the margin's allowance for the origin
// (traversal_margin.h: 16 ulps of it), and the fused step rounds once where
// the SSE test's subtraction and product round twice; so the box stays
// grown beyond every rounding, and the same hits are found. A zero
// direction component (infinite inverse) makes that axis's t NaN (or
// infinite), which leaves the running entry and exit as they were: the axis
// is then not used to cull, and the child is visited; an unused slot's
// empty box is still culled by the other axes (+inf entry, -inf exit), as
// long as origin' * inverse is finite there (bvhAvx2Suits).
#include <emmintrin.h>
#include <immintrin.h>

#include <atomic>
#include <bit>
#include <cmath>

#include "common/accel/bvh_node.h"
#include "common/accel/bvh_traverse_avx2.h"
#include "common/accel/grid_traversal.h"
#include "common/accel/triangle_intersect.h"

namespace portico {

namespace {
const bool kAvx2Supported = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
std::atomic<bool> avx2InUse{kAvx2Supported};
}  // namespace

bool bvhAvx2InUse() { return avx2InUse.load(std::memory_order_relaxed); }

void useBvhAvx2(bool use) { avx2InUse.store(use && kAvx2Supported, std::memory_order_relaxed); }

}  // namespace portico

#pragma GCC push_options
#pragma GCC target("avx2,fma")

#include "common/accel/bvh_traverse_loop.h"

namespace portico {

namespace {

struct Avx2Boxes {
  __m256 nearScaled[3], farScaled[3], inverse[3];   // origin' * inverse, near and far
  int nearSide[3];
  explicit Avx2Boxes(const BvhSlabs& slabs) {
    for (int axis = 0; axis < 3; ++axis) {
      nearScaled[axis] = _mm256_set1_ps(slabs.nearOrigin[axis] * slabs.inverse[axis]);
      farScaled[axis] = _mm256_set1_ps(slabs.farOrigin[axis] * slabs.inverse[axis]);
      inverse[axis] = _mm256_set1_ps(slabs.inverse[axis]);
      nearSide[axis] = slabs.nearSide[axis];
    }
  }
  // As SseBoxes::crossed4, eight boxes at once, each slab in one fused step.
  unsigned crossed(const BvhNode<8>& node, float tStart, float tLimit, float* entries) const {
    __m256 enter = _mm256_set1_ps(tStart), exit = _mm256_set1_ps(tLimit);
    for (int axis = 0; axis < 3; ++axis) {
      const __m256 nearBound = _mm256_load_ps(node.box[axis][nearSide[axis]]);
      const __m256 farBound = _mm256_load_ps(node.box[axis][1 - nearSide[axis]]);
      const __m256 tNear = _mm256_fmsub_ps(nearBound, inverse[axis], nearScaled[axis]);
      const __m256 tFar = _mm256_fmsub_ps(farBound, inverse[axis], farScaled[axis]);
      // NaN keeps the second operand, as with SSE.
      enter = _mm256_max_ps(tNear, enter);
      exit = _mm256_min_ps(tFar, exit);
    }
    _mm256_storeu_ps(entries, enter);
    return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(enter, exit, _CMP_LE_OQ)));
  }
};

}  // namespace

template <bool AnyHit>
bool traverseBvh8Avx2(const BvhData<8>& tree, const Ray& ray, const BvhSlabs& slabs, Hit& best) {
  return traverseBvh<8, AnyHit, Avx2Boxes>(tree, ray, slabs, best);
}

template bool traverseBvh8Avx2<false>(const BvhData<8>&, const Ray&, const BvhSlabs&, Hit&);
template bool traverseBvh8Avx2<true>(const BvhData<8>&, const Ray&, const BvhSlabs&, Hit&);

}  // namespace portico

#pragma GCC pop_options
