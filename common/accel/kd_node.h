// The flat form of a kd-tree: what every kd builder produces and what the
// traversal reads. Index-based and pointer-free (after pbrt's KdAccelNode and
// Tungsten's photon kd-tree), so it can be written to disk or sent over the
// wire as it is.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

#include "common/math.h"

namespace portico {

// One node in 8 bytes.
//
//   payload  interior: the split position (a float's bits).
//            leaf of one triangle: that triangle's primitive id.
//            other leaves: the index of the leaf's first entry in
//            KdTreeData::primitives.
//   bits     bits 0-1: the split axis (0, 1, 2) of an interior node, 3 for a
//            leaf. Bits 2-31: interior: the index of its first child (the
//            region below the split); the second child (above) is the next
//            node, so both share a cache line. Leaf: its triangle count.
struct KdNode {
  uint32_t payload = 0;
  uint32_t bits = 3;

  static constexpr uint32_t kLeafTag = 3;
  // Children indices and leaf sizes must fit in 30 bits.
  static constexpr uint32_t kMaxIndex = (uint32_t(1) << 30) - 1;

  static KdNode interior(int axis, float split, uint32_t firstChild) {
    return {std::bit_cast<uint32_t>(split), (firstChild << 2) | uint32_t(axis)};
  }
  static KdNode leaf(uint32_t triangleCount, uint32_t payload) {
    return {payload, (triangleCount << 2) | kLeafTag};
  }

  bool isLeaf() const { return (bits & 3) == kLeafTag; }
  int axis() const { return int(bits & 3); }
  float split() const { return std::bit_cast<float>(payload); }
  uint32_t firstChild() const { return bits >> 2; }
  uint32_t triangleCount() const { return bits >> 2; }
};
static_assert(sizeof(KdNode) == 8);

// Storage aligned to a cache line: the node layout (kd_layout.h) maps pairs
// of siblings onto 64-byte lines.
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

// A built kd-tree. nodes[0] is the root and nodes[1] unused padding (so that
// sibling pairs are 16-byte aligned); an empty tree (no triangle that can be
// hit) has no nodes.
struct KdTreeData {
  std::vector<KdNode, CacheLineAllocator<KdNode>> nodes;
  std::vector<uint32_t> primitives;  // the triangles of the leaves, leaf after leaf
  Bounds3 bounds;                    // of the triangles in the tree: the root's box

  // Filled by KdTreeWriter (kd_build.h) as leaves are made.
  uint64_t leaves = 0;
  uint64_t emptyLeaves = 0;
  uint64_t triangleReferences = 0;
  double depthSum = 0;  // over non-empty leaves, root = depth 1
  uint32_t maxDepth = 0;
};

}  // namespace portico
