// `bvh`'s traversal of 8-wide trees, compiled for AVX2: the eight children's
// boxes in one test. Chosen at run time (bvhAvx2InUse), so the program
// still runs on any x86-64. Every header is included before the target
// pragma, so the inline functions they define stay baseline code; only the
// loop (bvh_traverse_loop.h, internal linkage) and the box test below are
// compiled for AVX2. Same IEEE operations on the same values as the SSE
// test, no fused multiply-add (AVX2 does not include FMA), so the same
// children are visited and the same hits found.
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
const bool kAvx2Supported = __builtin_cpu_supports("avx2");
std::atomic<bool> avx2InUse{kAvx2Supported};
}  // namespace

bool bvhAvx2InUse() { return avx2InUse.load(std::memory_order_relaxed); }

void useBvhAvx2(bool use) { avx2InUse.store(use && kAvx2Supported, std::memory_order_relaxed); }

}  // namespace portico

#pragma GCC push_options
#pragma GCC target("avx2")

#include "common/accel/bvh_traverse_loop.h"

namespace portico {

namespace {

struct Avx2Boxes {
  __m256 nearOrigin[3], farOrigin[3], inverse[3];
  int nearSide[3];
  explicit Avx2Boxes(const BvhSlabs& slabs) {
    for (int axis = 0; axis < 3; ++axis) {
      nearOrigin[axis] = _mm256_set1_ps(slabs.nearOrigin[axis]);
      farOrigin[axis] = _mm256_set1_ps(slabs.farOrigin[axis]);
      inverse[axis] = _mm256_set1_ps(slabs.inverse[axis]);
      nearSide[axis] = slabs.nearSide[axis];
    }
  }
  // As SseBoxes::crossed4, eight boxes at once.
  unsigned crossed(const BvhNode<8>& node, float tStart, float tLimit, float* entries) const {
    __m256 enter = _mm256_set1_ps(tStart), exit = _mm256_set1_ps(tLimit);
    for (int axis = 0; axis < 3; ++axis) {
      const __m256 nearBound = _mm256_load_ps(node.box[axis][nearSide[axis]]);
      const __m256 farBound = _mm256_load_ps(node.box[axis][1 - nearSide[axis]]);
      const __m256 tNear = _mm256_mul_ps(_mm256_sub_ps(nearBound, nearOrigin[axis]), inverse[axis]);
      const __m256 tFar = _mm256_mul_ps(_mm256_sub_ps(farBound, farOrigin[axis]), inverse[axis]);
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
