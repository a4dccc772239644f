// `bvh`'s traversal of 8-wide trees, compiled for AVX2 and FMA: the eight
// children's boxes in one test. Chosen at run time (bvhAvx2InUse), so the
// program still runs on any x86-64. Every header is included before the
// target pragma, so the inline functions they define stay baseline code;
// only the loop (bvh_traverse_loop.h, internal linkage) and the box test
// below are compiled for AVX2, with the leaves' triangle test on eight
// lanes (testLeaf8). The box test takes each slab's distance in
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
// long as origin' * inverse is finite there (checked by WideBvh::traverse).
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

// The 8-lane form of testLeaf, for the AVX2 traversal: a leaf's packets two
// at a time (packet p in lanes 0-3, p + 1 in lanes 4-7; an odd last packet
// alone, its upper lanes off). Each lane computes grid_traversal::
// packetLanes's operations on its triangle, in the same order, so gets the
// same U, V, W, det and t bit for bit; a lane kept is then decided exactly as
// testLeaf decides it.
using Float8 = float __attribute__((vector_size(32)));
using Int8 = int32_t __attribute__((vector_size(32)));

inline Float8 broadcast8(float x) { return reinterpret_cast<Float8>(_mm256_set1_ps(x)); }   // bit for bit, -0 included

// grid_traversal::PacketRay on eight lanes: the same values, broadcast.
struct PacketRay8 {
  Float8 originX, originY, originZ, shearX, shearY, scaleZ, tMin, tMax;
  int kx, ky, kz;
  PacketRay8(const WatertightRay& frame, const Ray& ray) : kx(frame.kx), ky(frame.ky), kz(frame.kz) {
    const float origin[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
    originX = broadcast8(origin[kx]), originY = broadcast8(origin[ky]), originZ = broadcast8(origin[kz]);
    shearX = broadcast8(frame.Sx), shearY = broadcast8(frame.Sy), scaleZ = broadcast8(frame.Sz);
    tMin = broadcast8(ray.tMin), tMax = broadcast8(ray.tMax);
  }
};

// Bit k set where lane k of the mask is (every lane all ones or zero).
inline unsigned laneBits8(Int8 mask) { return unsigned(_mm256_movemask_ps(reinterpret_cast<__m256>(mask))); }

struct PacketLanes8 {
  Float8 t, det, V, W;
  unsigned candidates = 0, doubtful = 0;   // bit k: lane k (see grid_traversal::PacketLanes)
};

template <bool AnyHit>
inline PacketLanes8 packetLanes8(const grid_traversal::TrianglePacket& low, const grid_traversal::TrianglePacket& high,
                                 const PacketRay8& ray, float bestT) {
  const auto load = [&](int vertex, int axis) {
    grid_traversal::PacketRay::Float4 a, b;
    std::memcpy(&a, low.v[vertex][axis], sizeof(a));
    std::memcpy(&b, high.v[vertex][axis], sizeof(b));
    return __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7);
  };
  const Float8 az = load(0, ray.kz) - ray.originZ;
  const Float8 bz = load(1, ray.kz) - ray.originZ;
  const Float8 cz = load(2, ray.kz) - ray.originZ;
  const Float8 Ax = (load(0, ray.kx) - ray.originX) - ray.shearX * az;
  const Float8 Ay = (load(0, ray.ky) - ray.originY) - ray.shearY * az;
  const Float8 Bx = (load(1, ray.kx) - ray.originX) - ray.shearX * bz;
  const Float8 By = (load(1, ray.ky) - ray.originY) - ray.shearY * bz;
  const Float8 Cx = (load(2, ray.kx) - ray.originX) - ray.shearX * cz;
  const Float8 Cy = (load(2, ray.ky) - ray.originY) - ray.shearY * cz;
  PacketLanes8 lanes;
  const Float8 U = Cx * By - Cy * Bx;
  lanes.V = Ax * Cy - Ay * Cx;
  lanes.W = Bx * Ay - By * Ax;
  const Float8 zero{};
  const Int8 negative = (U < zero) | (lanes.V < zero) | (lanes.W < zero);
  const Int8 positive = (U > zero) | (lanes.V > zero) | (lanes.W > zero);
  const Int8 anyZero = (U == zero) | (lanes.V == zero) | (lanes.W == zero);
  const Int8 signsAgree = ~(negative & positive) | anyZero;
  if (laneBits8(signsAgree) == 0) return lanes;
  lanes.det = U + lanes.V + lanes.W;
  const Float8 T = U * (ray.scaleZ * az) + lanes.V * (ray.scaleZ * bz) + lanes.W * (ray.scaleZ * cz);
  lanes.t = T / lanes.det;
  Int8 inRange = (lanes.t > ray.tMin) & (lanes.t < ray.tMax);
  if constexpr (!AnyHit) inRange &= lanes.t <= Float8{bestT, bestT, bestT, bestT, bestT, bestT, bestT, bestT};
  lanes.candidates = laneBits8((signsAgree & inRange) | anyZero);
  lanes.doubtful = laneBits8(anyZero);
  return lanes;
}

template <bool AnyHit>
inline bool testLeaf8(const grid_traversal::TrianglePacket* packets, uint32_t child, const PacketRay8& packetRay,
                      const WatertightRay& frame, const Ray& ray, Hit& best) {
  const grid_traversal::TrianglePacket* packet = packets + bvh_child::firstPacket(child);
  const grid_traversal::TrianglePacket* const end = packet + bvh_child::packetCount(child);
  if (end - packet > 2) prefetchLeafTail(packet, end);   // the second pair's lines
  for (; packet < end; packet += 2) {
    const bool pair = packet + 1 != end;
    const PacketLanes8 lanes = packetLanes8<AnyHit>(*packet, pair ? packet[1] : *packet, packetRay, best.t);
    unsigned candidates = lanes.candidates & (pair ? 0xffu : 0x0fu);
    if (candidates == 0) continue;
    if constexpr (AnyHit) {
      if (candidates & ~lanes.doubtful) return true;
    }
    for (; candidates != 0; candidates &= candidates - 1) {
      const int lane = std::countr_zero(candidates);
      const grid_traversal::TrianglePacket& triangles = packet[lane >> 2];
      const int slot = lane & 3;
      if (takeLaneHit<AnyHit>(triangles, slot, (lanes.doubtful >> lane) & 1u, lanes.t[lane], lanes.V[lane],
                              lanes.W[lane], lanes.det[lane], frame, ray, best))
        return true;
    }
  }
  return false;
}

struct Avx2Boxes {
  __m256 nearScaled[3], farScaled[3], inverse[3];   // origin' * inverse, near and far
  int nearBound[3], farBound[3];                    // float offsets in a node of each axis's near and far bounds
  PacketRay8 packetRay;
  Avx2Boxes(const BvhSlabs& slabs, const WatertightRay& frame, const Ray& ray) : packetRay(frame, ray) {
#pragma GCC unroll 3
    for (int axis = 0; axis < 3; ++axis) {
      nearScaled[axis] = _mm256_set1_ps(slabs.nearScaled[axis]);
      farScaled[axis] = _mm256_set1_ps(slabs.farScaled[axis]);
      inverse[axis] = _mm256_set1_ps(slabs.inverse[axis]);
      nearBound[axis] = (2 * axis + slabs.nearSide[axis]) * 8;
      farBound[axis] = (2 * axis + 1 - slabs.nearSide[axis]) * 8;
    }
  }
  // As SseBoxes::crossed4, eight boxes at once, each slab in one fused step.
  unsigned crossed(const BvhNode<8>& node, float tStart, float tLimit, float* entries) const {
    const float* const bounds = &node.box[0][0][0];
    __m256 enter = _mm256_set1_ps(tStart), exit = _mm256_set1_ps(tLimit);
#pragma GCC unroll 3
    for (int axis = 0; axis < 3; ++axis) {
      const __m256 tNear = _mm256_fmsub_ps(_mm256_load_ps(bounds + nearBound[axis]), inverse[axis], nearScaled[axis]);
      const __m256 tFar = _mm256_fmsub_ps(_mm256_load_ps(bounds + farBound[axis]), inverse[axis], farScaled[axis]);
      // NaN keeps the second operand, as with SSE.
      enter = _mm256_max_ps(tNear, enter);
      exit = _mm256_min_ps(tFar, exit);
    }
    _mm256_storeu_ps(entries, enter);
    return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(enter, exit, _CMP_LE_OQ)));
  }
  // A leaf's packets two at a time.
  template <bool AnyHit>
  bool testLeaf(const grid_traversal::TrianglePacket* packets, uint32_t child, const WatertightRay& frame,
                const Ray& ray, Hit& best) const {
    return testLeaf8<AnyHit>(packets, child, packetRay, frame, ray, best);
  }
};

}  // namespace

template <bool AnyHit>
bool traverseBvh8Avx2(const BvhData<8>& tree, const Ray& ray, const BvhSlabs& slabs, const WatertightRay& frame,
                      Hit& best) {
  return traverseBvh<8, AnyHit, Avx2Boxes>(tree, ray, slabs, frame, best);
}

template bool traverseBvh8Avx2<false>(const BvhData<8>&, const Ray&, const BvhSlabs&, const WatertightRay&, Hit&);
template bool traverseBvh8Avx2<true>(const BvhData<8>&, const Ray&, const BvhSlabs&, const WatertightRay&, Hit&);

}  // namespace portico

#pragma GCC pop_options
