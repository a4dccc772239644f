// The kd-tree's leaves as 4-wide packets of copied vertices: what the
// traversal (kd_traverse.cpp) tests instead of following primitive ids into
// the mesh. Made from a built KdTreeData (kd_leaf_packets.cpp), so the
// builders do not know about them.
//
// Why: a leaf's triangles were tested one by one, each through two dependent
// loads (indices, then vertices) into the mesh. A packet holds four
// triangles' vertices side by side (grid_traversal::TrianglePacket, the
// layout the grid uses), so a leaf of up to four triangles costs one
// vector test with its loads independent of each other, and most misses
// never reach the scalar test at all.
#pragma once

#include <cstdint>
#include <cstring>
#include <new>
#include <vector>
#include <xmmintrin.h>

#include "common/accel/grid_traversal.h"
#include "common/accel/kd_node.h"
#include "common/accel/triangle_intersect.h"
#include "common/mesh_view.h"
#include "common/ray.h"

namespace portico::kd_leaf_packets {

using grid_traversal::PacketRay;
using grid_traversal::TrianglePacket;

// Storage aligned to a cache line, so that the node layout below maps onto lines.
template <typename T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlignment{64};
  CacheLineAllocator() = default;
  template <typename U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}
  T* allocate(size_t count) { return static_cast<T*>(::operator new(count * sizeof(T), kAlignment)); }
  void deallocate(T* pointer, size_t) noexcept { ::operator delete(pointer, kAlignment); }
  template <typename U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept { return true; }
};

// The traversal's copy of the tree: the nodes of KdTreeData, where every
// non-empty leaf's payload is the index of its first packet (its triangles
// fill ceil(count / 4) packets in order, the last padded with copies of the
// leaf's last triangle); interior nodes and empty leaves are unchanged.
//
// The same tree, but its sibling pairs laid out anew (nodes[0] is still the
// root, nodes[1] padding): the builders append a node's two children when
// they split it, depth first, so the pair below a node's lower child follows
// its own, while the pair below its upper child lies past the whole lower
// subtree, a cache miss for about every other step of a descent. Here each
// 64-byte line (four pairs) is filled with a small subtree, breadth first
// (a pair, the pairs of its two children, one grandchild pair), and the
// subtrees hanging below it follow depth first: every step from a line's
// first pair to its children stays in that line.
struct LeafPackets {
  std::vector<KdNode, CacheLineAllocator<KdNode>> nodes;
  std::vector<TrianglePacket> packets;
};

// Builds them from a tree over `mesh` (kd_leaf_packets.cpp).
void buildLeafPackets(const MeshView& mesh, const KdTreeData& tree, LeafPackets& out);

// Tests the `count` triangles of packets[0, ceil(count / 4)), folding hits
// into `best`; with AnyHit, returns true at the first hit.
//
// Exactness as in grid_traversal::testPackets (read its comment): on the
// four lanes, intersectTriangle's own steps (translation, shear, edge
// functions, sign test, det, T and t = T / det) run with the very
// operations of the scalar test (no contraction, -ffp-contract=off), so each
// lane gets the scalar U, V, W, det and t bit for bit. A lane is dropped only
// where intersectTriangle would return false on the same sign test or the
// same check of t against [tMin, tMax], or where its t would lose to the
// best hit so far (t > best.t never wins under closerThan); lanes with an
// edge function exactly zero (which the scalar test re-decides in double)
// and all the others go to intersectTriangle, on the packet's copies of
// the vertices (bit for bit the mesh's), which alone decides hits. Padding
// lanes are masked off.
template <bool AnyHit>
[[gnu::always_inline]] inline bool testLeafPackets(const TrianglePacket* packets, uint32_t count,
                                                   const PacketRay& packetRay, const WatertightRay& frame,
                                                   const Ray& ray, Hit& best) {
  using Float4 = PacketRay::Float4;
  using Int4 = int32_t __attribute__((vector_size(16)));
  const auto load = [](const float* p) {
    Float4 value;
    std::memcpy(&value, p, sizeof(value));
    return value;
  };
  const int kx = packetRay.kx, ky = packetRay.ky, kz = packetRay.kz;
  for (uint32_t first = 0; first < count; first += 4, ++packets) {
    const TrianglePacket& packet = *packets;
    const Float4 az = load(packet.v[0][kz]) - packetRay.originZ;
    const Float4 bz = load(packet.v[1][kz]) - packetRay.originZ;
    const Float4 cz = load(packet.v[2][kz]) - packetRay.originZ;
    const Float4 Ax = (load(packet.v[0][kx]) - packetRay.originX) - packetRay.shearX * az;
    const Float4 Ay = (load(packet.v[0][ky]) - packetRay.originY) - packetRay.shearY * az;
    const Float4 Bx = (load(packet.v[1][kx]) - packetRay.originX) - packetRay.shearX * bz;
    const Float4 By = (load(packet.v[1][ky]) - packetRay.originY) - packetRay.shearY * bz;
    const Float4 Cx = (load(packet.v[2][kx]) - packetRay.originX) - packetRay.shearX * cz;
    const Float4 Cy = (load(packet.v[2][ky]) - packetRay.originY) - packetRay.shearY * cz;
    const Float4 U = Cx * By - Cy * Bx;
    const Float4 V = Ax * Cy - Ay * Cx;
    const Float4 W = Bx * Ay - By * Ax;
    const Float4 zero{};
    const Int4 negative = (U < zero) | (V < zero) | (W < zero);
    const Int4 positive = (U > zero) | (V > zero) | (W > zero);
    const Int4 anyZero = (U == zero) | (V == zero) | (W == zero);
    const Float4 det = U + V + W;
    const Float4 T = U * (packetRay.scaleZ * az) + V * (packetRay.scaleZ * bz) + W * (packetRay.scaleZ * cz);
    const Float4 hitT = T / det;
    Int4 inRange = (hitT > packetRay.tMin) & (hitT < packetRay.tMax);
    if constexpr (!AnyHit) inRange &= hitT <= Float4{best.t, best.t, best.t, best.t};
    const Int4 candidate = (~(negative & positive) & inRange) | anyZero;
    unsigned mask = unsigned(_mm_movemask_ps(__m128(candidate)));  // the lanes' sign bits
    const uint32_t left = count - first;
    if (left < 4) mask &= (1u << left) - 1;
    while (mask != 0) {
      const int lane = __builtin_ctz(mask);
      mask &= mask - 1;
      const Vec3 v0{packet.v[0][0][lane], packet.v[0][1][lane], packet.v[0][2][lane]};
      const Vec3 v1{packet.v[1][0][lane], packet.v[1][1][lane], packet.v[1][2][lane]};
      const Vec3 v2{packet.v[2][0][lane], packet.v[2][1][lane], packet.v[2][2][lane]};
      float t, u, v;
      if (!intersectTriangle(frame, ray, v0, v1, v2, t, u, v)) continue;
      if constexpr (AnyHit) return true;
      const uint32_t primitive = packet.primitive[lane];
      if (closerThan(t, primitive, best)) best = Hit{t, primitive, u, v};
    }
  }
  return false;
}

}  // namespace portico::kd_leaf_packets
