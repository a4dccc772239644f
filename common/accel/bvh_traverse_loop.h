// The traversal loop of `bvh` (the reasoning is at the top of
// bvh_traverse.cpp), written once and compiled twice: by bvh_traverse.cpp
// for any x86-64 (SSE, four children per box test) and by
// bvh_traverse_avx2.cpp for 8-wide trees on machines with AVX2 (eight per
// test). Everything here has internal linkage, so the two compilations,
// whose instruction sets differ, never stand in for each other at link time.
// Include only from those two files.
#pragma once

#include <emmintrin.h>

#include <bit>
#include <cmath>
#include <cstdint>

#include "common/accel/bvh_node.h"
#include "common/accel/bvh_traverse_avx2.h"
#include "common/accel/grid_traversal.h"
#include "common/accel/triangle_intersect.h"

namespace portico {
namespace {

struct BvhStackEntry {
  uint32_t child;
  float entry;
};

// Tests a leaf's packets, folding hits into best; with AnyHit, true at the
// first hit. A lane the 4-wide test keeps with no edge function zero is a
// hit of intersectTriangle with the lane's t, and u = V / det, v = W / det
// (the same divisions): its sign test and range check passed on the scalar
// test's own values; det is not zero (t would be infinite or NaN and fail
// the strict range check); the scalar test's exact check of T / det against
// [tMin, tMax] in double agrees with its check of the rounded t (rounding
// is monotone and the bounds are floats); and degenerate triangles are not
// in the tree. Lanes with a zero edge function go to intersectTriangle,
// which re-decides them in double.
// One candidate lane of a leaf's packet (triangle `slot`), decided as said
// above: a doubtful lane by intersectTriangle, any other with the lane's own
// t and divisions; the nearer hit goes to `best`. True when an any-hit query
// may stop.
template <bool AnyHit>
inline bool takeLaneHit(const grid_traversal::TrianglePacket& triangles, int slot, bool doubtful, float t, float V,
                        float W, float det, const WatertightRay& frame, const Ray& ray, Hit& best) {
  const uint32_t primitive = triangles.primitive[slot];
  Hit hit{t, primitive, 0, 0};
  if (doubtful) {
    const Vec3 v0{triangles.v[0][0][slot], triangles.v[0][1][slot], triangles.v[0][2][slot]};
    const Vec3 v1{triangles.v[1][0][slot], triangles.v[1][1][slot], triangles.v[1][2][slot]};
    const Vec3 v2{triangles.v[2][0][slot], triangles.v[2][1][slot], triangles.v[2][2][slot]};
    if (!intersectTriangle(frame, ray, v0, v1, v2, hit.t, hit.u, hit.v)) return false;
    if constexpr (AnyHit) return true;
  } else {
    if (!closerThan(hit.t, primitive, best)) return false;
    hit.u = V / det;
    hit.v = W / det;
  }
  if (closerThan(hit.t, primitive, best)) best = hit;
  return false;
}

template <bool AnyHit>
inline bool testLeaf(const grid_traversal::TrianglePacket* packets, uint32_t child,
                     const grid_traversal::PacketRay& packetRay, const WatertightRay& frame, const Ray& ray,
                     Hit& best) {
  const grid_traversal::TrianglePacket* packet = packets + bvh_child::firstPacket(child);
  const grid_traversal::TrianglePacket* const end = packet + bvh_child::packetCount(child);
  for (; packet != end; ++packet) {
    const grid_traversal::PacketLanes lanes = grid_traversal::packetLanes<AnyHit>(*packet, packetRay, best.t);
    unsigned candidates = grid_traversal::laneBits(lanes.candidate);
    if (candidates == 0) continue;
    if constexpr (AnyHit) {
      if (candidates & ~grid_traversal::laneBits(lanes.anyZero)) return true;
    }
    const unsigned doubtful = grid_traversal::laneBits(lanes.anyZero);
    for (; candidates != 0; candidates &= candidates - 1) {
      const int lane = std::countr_zero(candidates);
      if (takeLaneHit<AnyHit>(*packet, lane, (doubtful >> lane) & 1u, lanes.t[lane], lanes.V[lane], lanes.W[lane],
                              lanes.det[lane], frame, ray, best))
        return true;
    }
  }
  return false;
}

// SSE: four children per test; an 8-wide node takes two.
struct SseBoxes {
  __m128 nearOrigin[3], farOrigin[3], inverse[3];
  int nearSide[3];
  grid_traversal::PacketRay packetRay;
  SseBoxes(const BvhSlabs& slabs, const WatertightRay& frame, const Ray& ray) : packetRay(frame, ray) {
    for (int axis = 0; axis < 3; ++axis) {
      nearOrigin[axis] = _mm_set1_ps(slabs.nearOrigin[axis]);
      farOrigin[axis] = _mm_set1_ps(slabs.farOrigin[axis]);
      inverse[axis] = _mm_set1_ps(slabs.inverse[axis]);
      nearSide[axis] = slabs.nearSide[axis];
    }
  }
  // Where the ray enters each of four boxes (the latest entry over the axes
  // and tStart), and which it crosses before tLimit (bit k: box k). Box k's
  // bounds are box[axis][side][offset + k].
  template <int Width>
  unsigned crossed4(const BvhNode<Width>& node, int offset, __m128 tStart, __m128 tLimit, float* entries) const {
    __m128 enter = tStart, exit = tLimit;
    for (int axis = 0; axis < 3; ++axis) {
      const __m128 nearBound = _mm_load_ps(node.box[axis][nearSide[axis]] + offset);
      const __m128 farBound = _mm_load_ps(node.box[axis][1 - nearSide[axis]] + offset);
      const __m128 tNear = _mm_mul_ps(_mm_sub_ps(nearBound, nearOrigin[axis]), inverse[axis]);
      const __m128 tFar = _mm_mul_ps(_mm_sub_ps(farBound, farOrigin[axis]), inverse[axis]);
      // NaN (an origin on a face of a slab the ray runs in) keeps the second operand.
      enter = _mm_max_ps(tNear, enter);
      exit = _mm_min_ps(tFar, exit);
    }
    _mm_storeu_ps(entries, enter);
    return unsigned(_mm_movemask_ps(_mm_cmple_ps(enter, exit)));
  }
  template <int Width>
  unsigned crossed(const BvhNode<Width>& node, float tStart, float tLimit, float* entries) const {
    const __m128 start = _mm_set1_ps(tStart), limit = _mm_set1_ps(tLimit);
    unsigned bits = crossed4(node, 0, start, limit, entries);
    if constexpr (Width == 8) bits |= crossed4(node, 4, start, limit, entries + 4) << 4;
    return bits;
  }
  template <bool AnyHit>
  bool testLeaf(const grid_traversal::TrianglePacket* packets, uint32_t child, const WatertightRay& frame,
                const Ray& ray, Hit& best) const {
    return portico::testLeaf<AnyHit>(packets, child, packetRay, frame, ray, best);
  }
};

// Starts the cache misses of a leaf's lines past its first 256 bytes: a
// leaf of four packets spans ten lines, and the loads of its second pair
// would otherwise wait for the first pair's test (its branches mispredict).
inline void prefetchLeafTail(const grid_traversal::TrianglePacket* first, const grid_traversal::TrianglePacket* end) {
  const char* const last = reinterpret_cast<const char*>(end);
  for (const char* line = reinterpret_cast<const char*>(first) + 256; line < last; line += 64) __builtin_prefetch(line);
}

// Where a child's node or first packet starts.
template <int Width>
inline const char* childAddress(const BvhNode<Width>* nodes, const grid_traversal::TrianglePacket* packets,
                                uint32_t child) {
  // Both computed, one chosen by a mask: no branch to mispredict (GCC
  // turns the plain conditional into one).
  const uintptr_t leaf = reinterpret_cast<uintptr_t>(packets) +
                         uintptr_t(bvh_child::firstPacket(child)) * sizeof(grid_traversal::TrianglePacket);
  const uintptr_t node = reinterpret_cast<uintptr_t>(nodes) + uintptr_t(child) * sizeof(BvhNode<Width>);
  const uintptr_t leafMask = uintptr_t(0) - uintptr_t(child >> 31);
  return reinterpret_cast<const char*>((leaf & leafMask) | (node & ~leafMask));
}

// Starts the cache misses of a child's lines (a node's four, a leaf's
// whole), for when it is popped.
template <int Width>
inline void prefetchChild(const BvhNode<Width>* nodes, const grid_traversal::TrianglePacket* packets, uint32_t child) {
  const char* const address = childAddress(nodes, packets, child);
  __builtin_prefetch(address);
  __builtin_prefetch(address + 64);
  __builtin_prefetch(address + 128);
  __builtin_prefetch(address + 192);
  if (bvh_child::isLeaf(child) && bvh_child::packetCount(child) > 1) {
    const grid_traversal::TrianglePacket* const first = packets + bvh_child::firstPacket(child);
    prefetchLeafTail(first, first + bvh_child::packetCount(child));
  }
}

// Nearest hit (or, with AnyHit, any hit) of the ray in the tree, from the
// root; result holds what was found. The ray is finite, with tMin < tMax,
// and slabs and frame hold its constants.
template <int Width, bool AnyHit, class Boxes>
[[gnu::flatten]] bool traverseBvh(const BvhData<Width>& tree, const Ray& ray, const BvhSlabs& slabs,
                                   const WatertightRay& frame, Hit& result) {
  Hit best = result;   // a local copy: the stack's stores cannot alias it, so best.t stays in a register
  const Boxes boxes(slabs, frame, ray);
  const BvhNode<Width>* const nodes = tree.nodes.data();
  const grid_traversal::TrianglePacket* const packets = tree.packets.data();
  BvhStackEntry stack[(Width - 1) * kBvhMaxDepth + 1];
  int pending = 0;
  uint32_t current = 0;   // the root

  for (;;) {
    // Down the nodes, nearest child first, stacking the others the ray enters.
    while (!bvh_child::isLeaf(current)) {
      const BvhNode<Width>& node = nodes[current];
      float entries[Width];
      unsigned crossed = boxes.crossed(node, ray.tMin, best.t < ray.tMax ? best.t : ray.tMax, entries);
      if (crossed == 0) goto nextStacked;
      const int nearest = std::countr_zero(crossed);
      const unsigned others = crossed & (crossed - 1);
      if (others == 0) {
        current = node.child[nearest];
        continue;
      }
      if ((others & (others - 1)) == 0) {
        // Two: the farther stacked (its cache misses started now), the nearer next.
        const int second = std::countr_zero(others);
        const bool secondNearer = entries[second] < entries[nearest];
        const int nearK = secondNearer ? second : nearest, farK = secondNearer ? nearest : second;
        const BvhStackEntry far{node.child[farK], entries[farK]};
        prefetchChild(nodes, packets, far.child);
        stack[pending++] = far;
        current = node.child[nearK];
        continue;
      }
      // Three or more: sorted farthest first onto the stack; the nearest is
      // next. Each is loaded soon (the nearest next, the others when
      // popped): start their cache misses now, side by side.
      BvhStackEntry* const first = stack + pending;
      for (; crossed != 0; crossed &= crossed - 1) {
        const int k = std::countr_zero(crossed);
        const BvhStackEntry entry{node.child[k], entries[k]};
        prefetchChild(nodes, packets, entry.child);
        BvhStackEntry* slot = stack + pending++;
        while (slot != first && slot[-1].entry < entry.entry) {
          *slot = slot[-1];
          --slot;
        }
        *slot = entry;
      }
      current = stack[--pending].child;
    }

    if (boxes.template testLeaf<AnyHit>(packets, current, frame, ray, best) && AnyHit) {
      result = best;
      return true;
    }

  nextStacked:
    // The next stacked child that may hold a hit at best.t or nearer.
    for (;;) {
      if (pending == 0) {
        result = best;
        return best.found();
      }
      const BvhStackEntry& next = stack[--pending];
      if (!AnyHit && best.t < next.entry) continue;
      current = next.child;
      break;
    }
  }
}


}  // namespace
}  // namespace portico
